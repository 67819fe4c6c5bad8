"""ArduPilot DataFlash logs: a real JSBSim flight written by the recorder bridge as an
ArduPlane vehicle logs it, read back with pymavlink's DFReader in the loop, equals the
flight within the logging's quantization; the commands are marked as commands."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from pymavlink import DFReader, mavutil
from typer.testing import CliRunner

from flightid.api import fly
from flightid.cli.app import app
from flightid.identification.data.windows import window
from flightid.importers.dataflash import read_dataflash, servos_from_params
from flightid.importers.servos import Servo, ServoMapping, Throttle, read_servo_map
from flightid.record import read
from flightid.sim.bridge.air.dataflash import BOOT_S, RATES, SysIdRun, write_dataflash
from flightid.units import DEG

F32 = 2.0**-24  # float32 relative rounding
CENTIDEGREE = 0.005 * DEG  # half a centidegree (ATT's int16 fields)
# an asymmetric, offset-trim, reversed elevator and an offset throttle
SERVOS = ServoMapping({"da": Servo(1, 1510, 25 * DEG), "de": Servo(2, 1480, -20 * DEG,
                                                                    -15 * DEG),
                       "dr": Servo(4, 1500, 30 * DEG)}, Throttle(3, 1100, 1900))
# channel -> (message, the logging's largest error)
QUANTIZATION = {
    "p": ("IMU", "f32"), "q": ("IMU", "f32"), "r": ("IMU", "f32"), "ax": ("IMU", "f32"),
    "ay": ("IMU", "f32"), "az": ("IMU", "f32"),
    "phi": ("ATT", CENTIDEGREE), "theta": ("ATT", CENTIDEGREE),
    "alpha": ("AOA", "f32"), "beta": ("AOA", "f32"),
    "V": ("ARSP", "f32"), "qbar": ("ARSP", "f32"),
    # half a microsecond of PWM: the throw per 500 us / 1000
    "da": ("RCOU", 25 * DEG / 1000), "de": ("RCOU", 20 * DEG / 1000),
    "dr": ("RCOU", 30 * DEG / 1000), "throttle": ("RCOU", 0.5 / 800),
    # float32 static pressure near 1e5 Pa: half an ulp (0.004 Pa) over rho g (12 Pa/m)
    "h": ("BARO", 1e-3),
    "latitude": ("GPS", 0.5e-7 * DEG), "longitude": ("GPS", 0.5e-7 * DEG),
}


@pytest.fixture(scope="module")
def flown():
    return fly("telemaster-id", seed=1)


@pytest.fixture(scope="module")
def flight(flown):
    # the Telemaster (an RC airplane) through elevator, rudder and aileron inputs; the
    # exact flight at 100 Hz, so every message rate samples it without interpolation
    return flown.truth_record


@pytest.fixture(scope="module")
def log(flight, tmp_path_factory):
    path = tmp_path_factory.mktemp("df") / "flight.bin"
    return write_dataflash(flight, path, servos=SERVOS)


def test_pymavlink_reads_the_log_as_arduplane_messages(log, flight):
    reader = DFReader.DFReader_binary(str(log))
    counts: dict[str, int] = {}
    first = {}
    while (m := reader.recv_msg()) is not None:
        counts[m.get_type()] = counts.get(m.get_type(), 0) + 1
        first.setdefault(m.get_type(), m)
    span = flight.time[-1] - flight.time[0]
    for name, rate in RATES.items():
        assert counts[name] == int(span * rate + 1e-6) + 1, name
    assert first["IMU"].TimeUS == round(BOOT_S * 1e6)
    assert first["ATT"].Roll == pytest.approx(flight["phi"][0] / DEG, abs=0.005)
    # the FMTU metadata gives ArduPilot's units (what MAVExplorer shows)
    assert reader.formats[reader.name_to_id["IMU"]].units[2] == "rad/s"
    assert reader.formats[reader.name_to_id["RCOU"]].units[1] == "PWM"


def test_the_read_log_equals_the_flight_within_the_quantization(log, flight):
    back = read_dataflash(log, SERVOS)
    assert back.meta.extra["surfaces"] == "command"
    assert back.meta.extra["dataflash"]["dropped_bytes"] == 0
    t = back.time - BOOT_S + flight.time[0]
    assert back.dt == pytest.approx(1 / RATES["IMU"], rel=1e-9)
    worst = {}
    for name, (message, q) in QUANTIZATION.items():
        # each channel was logged at its message's times and interpolated onto the grid:
        # interpolating the exact flight the same way leaves only the logging's rounding
        times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9,
                                           1 / RATES[message])
        expected = np.interp(t, times, np.interp(times, flight.time, flight[name]))
        tol = F32 * 2 * np.max(np.abs(flight[name])) if q == "f32" else q
        if name == "V":  # EAS in float32 and back with the ISA density at h
            tol = 4 * F32 * np.max(flight["V"])
        worst[name] = float(np.max(np.abs(back[name] - expected)))
        assert worst[name] <= tol * (1 + 1e-9), (name, worst[name], tol)
    psi_times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9, 1 / RATES["ATT"])
    psi = np.interp(t, psi_times, np.interp(psi_times, flight.time, np.unwrap(flight["psi"])))
    assert np.max(np.abs(np.angle(np.exp(1j * (back["psi"] - psi))))) <= CENTIDEGREE


def test_import_command_reads_a_dataflash_log(log, tmp_path):
    servo_map = tmp_path / "servos.toml"
    servo_map.write_text("""[da]
channel = 1
trim = 1510
throw = "25 deg"
[de]
channel = 2
trim = 1480
throw = "-20 deg"
throw_low = "-15 deg"
[dr]
channel = 4
throw = "30 deg"
[throttle]
channel = 3
low = 1100
high = 1900
""")
    out = tmp_path / "flight.parquet"
    result = CliRunner().invoke(app, ["import", str(log), "-o", str(out), "--servos",
                                      str(servo_map), "--aircraft", "telemaster"])
    assert result.exit_code == 0, result.output
    assert "commands" in result.output
    rec, direct = read(out), read_dataflash(log, SERVOS)
    for name in ("de", "da", "dr", "throttle", "q", "V"):
        np.testing.assert_array_equal(rec[name], direct[name])
    assert rec.meta.extra["surfaces"] == "command" and rec.meta.reference is not None


def test_a_cut_log_keeps_what_is_whole_and_says_what_was_dropped(log, tmp_path):
    data = log.read_bytes()
    cut = tmp_path / "cut.bin"
    cut.write_bytes(data[: len(data) // 2 + 7])
    back = read_dataflash(cut, SERVOS)
    info = back.meta.extra["dataflash"]
    assert 0 < info["dropped_bytes"] < 60  # less than one message (IMU: 3 + 51 bytes)
    assert any("cut message" in n for n in info["notes"])
    whole = read_dataflash(log, SERVOS)
    n = len(back)
    assert 0.4 * len(whole) < n < 0.6 * len(whole)
    np.testing.assert_array_equal(back["q"], whole["q"][:n])


def test_a_log_without_the_needed_messages_is_refused_naming_them(flight, tmp_path):
    path = write_dataflash(flight, tmp_path / "no_att.bin", servos=SERVOS,
                           rates={"ATT": 0, "ARSP": 0, "CTUN": 0})
    with pytest.raises(ValueError, match=r"lacks the message\(s\) ATT, ARSP or CTUN"):
        read_dataflash(path, SERVOS)
    result = CliRunner().invoke(app, ["import", str(path), "-o", str(tmp_path / "x.parquet")])
    assert result.exit_code == 2 and "ATT, ARSP or CTUN" in result.output


def test_a_servo_map_to_an_unknown_channel_is_refused_naming_the_valid_ones(log, tmp_path):
    servo_map = tmp_path / "servos.toml"
    servo_map.write_text("[elevator]\nchannel = 2\n")
    result = CliRunner().invoke(app, ["import", str(log), "-o", str(tmp_path / "x.parquet"),
                                      "--servos", str(servo_map)])
    assert result.exit_code == 2
    assert "'elevator' is not a control channel; valid: de, da, dr, df, throttle" in \
        result.output


def test_system_identification_chirps_become_maneuver_windows(flight, tmp_path):
    # the elevator maneuver at 1.0-1.9 s and the rudder one at 8.0-9.0 s logged as
    # SID_AXIS 11 (pitch mixer) and 12 (yaw mixer) runs
    runs = [SysIdRun(11, 1.0, 0.9, 0.5, 5.0), SysIdRun(12, 8.0, 0.8, 0.5, 5.0,
                                                       fade_out_s=0.2)]
    path = write_dataflash(flight, tmp_path / "sysid.bin", servos=SERVOS, sysid=runs)
    back = read_dataflash(path, SERVOS)
    found = back.meta.extra["maneuvers"]
    assert [m["surfaces"] for m in found] == [["de"], ["dr"]]
    assert [m["kind"] for m in found] == ["chirp", "chirp"]
    for m, run in zip(found, runs, strict=True):
        assert m["start"] == pytest.approx(run.start + BOOT_S, abs=1e-6)
        # SIDD at the IMU's 50 Hz: the last one TR + TFout after the start
        assert m["end"] == pytest.approx(run.start + BOOT_S + run.record_s + run.fade_out_s,
                                         abs=1e-6)
        assert m["f_start_hz"] == run.f_start_hz and m["f_stop_hz"] == run.f_stop_hz
    # the methods' window on the elevator: 1 s before the chirp, up to the next maneuver
    assert window(back, ["de"]) == pytest.approx((BOOT_S, 8.0 + BOOT_S))


def test_damage_inside_a_log_is_skipped_and_counted(log, tmp_path):
    data = log.read_bytes()
    k = len(data) // 2
    junk = bytes(np.random.default_rng(0).integers(0, 256, 100, dtype=np.uint8))
    damaged = tmp_path / "damaged.bin"
    damaged.write_bytes(data[:k] + junk + data[k:])
    back, whole = read_dataflash(damaged, SERVOS), read_dataflash(log, SERVOS)
    assert len(back) == len(whole)
    notes = back.meta.extra["dataflash"]["notes"]
    assert any("unreadable byte(s) skipped" in n for n in notes), notes


def test_a_file_that_is_not_a_dataflash_log_is_refused(tmp_path):
    path = tmp_path / "photo.bin"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    with pytest.raises(ValueError, match="not a DataFlash log: it does not start with"):
        read_dataflash(path)


def test_without_a_mapping_the_logs_servo_parameters_give_outputs_and_trims(flight, tmp_path):
    # outputs moved off ArduPlane's default order, offset trims, a reversed elevator, a
    # 1100-1900 us throttle; throws of 30 deg, the value assumed without a mapping
    servos = ServoMapping({"da": Servo(5, 1490), "de": Servo(6, 1520, -30 * DEG),
                           "dr": Servo(7, 1505)}, Throttle(8, 1100, 1900))
    path = write_dataflash(flight, tmp_path / "params.bin", servos=servos)
    back, given = read_dataflash(path), read_dataflash(path, servos)
    for name in ("da", "de", "dr", "throttle"):
        np.testing.assert_allclose(back[name], given[name], rtol=0, atol=1e-12)
    assert back.meta.extra["dataflash"]["servos"]["de"]["channel"] == 6
    assert any("30 deg assumed" in n for n in back.meta.extra["dataflash"]["notes"])


def test_mavexplorers_loader_reads_the_log(log):
    """MAVExplorer's ``loadfile`` (MAVProxy's tools/MAVExplorer.py) opens a log with
    ``mavutil.mavlink_connection(path, notimestamps=False, zero_time_base=False,
    progress_callback=...)`` and then uses the reader's messages, count, parameters and
    flight modes; the same calls, headless. pymavlink's mavlogdump reads it too."""
    progress = []
    mlog = mavutil.mavlink_connection(str(log), notimestamps=False, zero_time_base=False,
                                      progress_callback=progress.append)
    assert isinstance(mlog, DFReader.DFReader_binary)
    assert {"IMU", "ATT", "ARSP", "CTUN", "RCOU", "BARO", "GPS"} <= set(mlog.messages)
    counts: dict[str, int] = {}
    whole = DFReader.DFReader_binary(str(log))
    while (m := whole.recv_msg()) is not None:
        counts[m.get_type()] = counts.get(m.get_type(), 0) + 1
    assert mlog._count == sum(counts.values()) and progress and progress[-1] >= 98
    assert mlog.params["SERVO2_FUNCTION"] == 19 and mlog.params["SERVO2_TRIM"] == 1480
    assert mlog.flightmode_list() is not None
    dump = subprocess.run([sys.executable, "-m", "pymavlink.tools.mavlogdump", "--types",
                           "ATT", "--format", "csv", str(log)], capture_output=True,
                          text=True, check=True)
    rows = dump.stdout.strip().splitlines()
    assert rows[0].startswith("timestamp,TimeUS,DesRoll,Roll")
    assert len(rows) - 1 == counts["ATT"]


def test_without_arsp_the_airspeed_comes_from_ctun(log, flight, tmp_path):
    path = write_dataflash(flight, tmp_path / "ctun.bin", servos=SERVOS, rates={"ARSP": 0})
    back, whole = read_dataflash(path, SERVOS), read_dataflash(log, SERVOS)
    assert "qbar" not in back and any("airspeed from CTUN" in n for n in
                                      back.meta.extra["dataflash"]["notes"])
    # CTUN logs the same float32 equivalent airspeed at ARSP's 10 Hz
    np.testing.assert_allclose(back["V"], whole["V"], rtol=0, atol=4 * F32 * np.max(flight["V"]))


def test_ardupilot_outputs_above_trim_ask_for_positive_moments(flown):
    """ArduPilot's aileron, elevator and rudder outputs are roll, pitch and yaw demands:
    above trim on an output not reversed (below it on a reversed one) a right roll, nose
    up, nose right. Read as flightid's deflections and put through the Telemaster's own
    control derivatives (flightid's signs: Cl_da, Cm_de, Cn_dr < 0), each gives that
    positive moment; 100 us of 500 at the assumed 30 deg throw is 6 deg."""
    truth = flown.truth
    params = {"SERVO1_FUNCTION": 4, "SERVO2_FUNCTION": 19, "SERVO4_FUNCTION": 21,
              "SERVO4_REVERSED": 1, "SERVO3_FUNCTION": 70}
    for servos in (servos_from_params(params), ServoMapping()):
        da = servos.surfaces["da"].deflection(1600.0)
        de = servos.surfaces["de"].deflection(1600.0)
        assert da == pytest.approx(-6 * DEG) and de == pytest.approx(-6 * DEG)
        assert truth["Cl_da"] * da > 0 and truth["Cm_de"] * de > 0
    dr = servos_from_params(params).surfaces["dr"].deflection(1400.0)
    assert dr == pytest.approx(-6 * DEG) and truth["Cn_dr"] * dr > 0


def test_an_off_centre_trim_scales_the_demand_as_ardupilot_does():
    """ArduPilot puts a demand d (-1..1) out as trim + d (max - trim) above trim and
    trim + d (trim - min) below it (SRV_Channel::pwm_from_angle). With SERVOn_MIN 1100,
    _MAX 1900 and a 1600 us trim, a full demand either way (1900 or 1100 us) is the same
    deflection: 30 deg per 500 us above trim, 300 us of it."""
    servos = servos_from_params({"SERVO1_FUNCTION": 4, "SERVO1_TRIM": 1600,
                                 "SERVO1_MIN": 1100, "SERVO1_MAX": 1900})
    aileron = servos.surfaces["da"]
    assert aileron.deflection(1900.0) == pytest.approx(-18 * DEG)
    assert aileron.deflection(1100.0) == pytest.approx(18 * DEG)
    assert aileron.deflection(1350.0) == pytest.approx(9 * DEG)  # half a demand


def test_a_throw_below_trim_is_a_size_with_the_throws_sign(tmp_path):
    """throw_low given as a size ("15 deg") or with the throw's sign ("-15 deg") is the
    same servo: 500 us below trim moves a reversed elevator 15 deg the other way."""
    for low in ("15 deg", "-15 deg"):
        path = tmp_path / "servos.toml"
        path.write_text(f'[de]\nchannel = 2\ntrim = 1480\nthrow = "-20 deg"\n'
                        f'throw_low = "{low}"\n')
        elevator = read_servo_map(path).surfaces["de"]
        assert elevator.deflection(980.0) == pytest.approx(15 * DEG)
        assert elevator.deflection(1980.0) == pytest.approx(-20 * DEG)
