"""PX4 ULog files: a real JSBSim flight written by the recorder bridge's ULog writer,
read back through pyulog, equals the flight within the logging's quantization; the
actuator outputs are marked as commands."""

from __future__ import annotations

import numpy as np
import pytest
from pyulog import ULog
from typer.testing import CliRunner

from flightid.api import fly
from flightid.cli.app import app
from flightid.importers.servos import Servo, ServoMapping, Throttle
from flightid.importers.ulog import read_ulog
from flightid.record import read
from flightid.sim.bridge.air.dataflash import BOOT_S
from flightid.sim.bridge.air.ulog import RATES, write_ulog
from flightid.units import DEG

F32 = 2.0**-24  # float32 relative rounding
SERVOS = ServoMapping({"da": Servo(1, 1510, 25 * DEG), "de": Servo(2, 1480, -20 * DEG,
                                                                    -15 * DEG),
                       "dr": Servo(4, 1500, 30 * DEG)}, Throttle(3, 1100, 1900))
# channel -> (topic, the logging's largest error)
QUANTIZATION = {
    "p": ("vehicle_angular_velocity", "f32"), "q": ("vehicle_angular_velocity", "f32"),
    "r": ("vehicle_angular_velocity", "f32"), "ax": ("sensor_combined", "f32"),
    "ay": ("sensor_combined", "f32"), "az": ("sensor_combined", "f32"),
    # a float32 quaternion: each component within 2^-24, the angles within about 2 of it
    "phi": ("vehicle_attitude", 4 * F32), "theta": ("vehicle_attitude", 4 * F32),
    "V": ("airspeed", "f32"), "qbar": ("differential_pressure", "f32"),
    "alpha": ("airflow_aoa", "f32"), "beta": ("airflow_slip", "f32"),
    "h": ("vehicle_air_data", "f32"),
    "da": ("actuator_outputs", 25 * DEG / 1000), "de": ("actuator_outputs", 20 * DEG / 1000),
    "dr": ("actuator_outputs", 30 * DEG / 1000), "throttle": ("actuator_outputs", 0.5 / 800),
    "latitude": ("vehicle_global_position", 1e-15), "longitude": ("vehicle_global_position",
                                                                  1e-15),
}


@pytest.fixture(scope="module")
def flight():
    return fly("telemaster-id", seed=1).truth_record


@pytest.fixture(scope="module")
def log(flight, tmp_path_factory):
    return write_ulog(flight, tmp_path_factory.mktemp("ulg") / "flight.ulg", servos=SERVOS)


def test_pyulog_reads_the_topics_at_their_rates(log, flight):
    ulog = ULog(str(log))
    assert not ulog.file_corruption
    span = flight.time[-1] - flight.time[0]
    for data in ulog.data_list:
        assert len(data.data["timestamp"]) == int(span * RATES[data.name] + 1e-6) + 1
        assert data.data["timestamp"][0] == round(BOOT_S * 1e6)


def test_the_read_log_equals_the_flight_within_the_quantization(log, flight):
    back = read_ulog(log, SERVOS)
    assert back.meta.extra["surfaces"] == "command"
    t = back.time - BOOT_S + flight.time[0]
    for name, (topic, q) in QUANTIZATION.items():
        # each channel at its topic's times, interpolated onto the grid: the exact flight
        # interpolated the same way leaves only the logging's rounding
        times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9, 1 / RATES[topic])
        expected = np.interp(t, times, np.interp(times, flight.time, flight[name]))
        tol = 2 * F32 * np.max(np.abs(flight[name])) if q == "f32" else q
        worst = float(np.max(np.abs(back[name] - expected)))
        assert worst <= tol * (1 + 1e-9), (name, worst, tol)
    times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9,
                                       1 / RATES["vehicle_attitude"])
    psi = np.interp(t, times, np.interp(times, flight.time, np.unwrap(flight["psi"])))
    assert np.max(np.abs(np.angle(np.exp(1j * (back["psi"] - psi))))) <= 4 * F32 * np.pi


def test_import_command_reads_a_ulog_file(log, tmp_path):
    out = tmp_path / "flight.parquet"
    result = CliRunner().invoke(app, ["import", str(log), "-o", str(out), "--aircraft",
                                      "telemaster"])
    assert result.exit_code == 0, result.output
    assert "servo commands (actuator_outputs" in result.output
    rec = read(out)
    assert rec.meta.extra["surfaces"] == "command" and "mass" in rec


def test_a_cut_file_keeps_what_is_whole_and_says_so(log, flight, tmp_path):
    data = log.read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: len(data) // 2 + 5])
    back, whole = read_ulog(cut, SERVOS), read_ulog(log, SERVOS)
    assert any("ends in a cut message" in n for n in back.meta.extra["ulog"]["notes"])
    n = len(back)
    assert 0.4 * len(whole) < n < 0.6 * len(whole)
    np.testing.assert_array_equal(back["q"], whole["q"][:n])


def test_a_log_without_the_needed_topics_is_refused_naming_them(flight, tmp_path):
    path = write_ulog(flight, tmp_path / "no_attitude.ulg", servos=SERVOS,
                      rates={"vehicle_attitude": 0, "actuator_outputs": 0})
    with pytest.raises(ValueError, match=r"lacks the topic\(s\) vehicle_attitude, "
                                         r"actuator_outputs or actuator_servos"):
        read_ulog(path, SERVOS)


def test_without_a_mapping_the_logs_px4_parameters_give_outputs_and_trims(flight, tmp_path):
    # outputs off ArduPlane's order, offset trims, a reversed elevator, a 1100-1900 us
    # throttle; throws of 30 deg, the value assumed without a mapping
    servos = ServoMapping({"da": Servo(5, 1490), "de": Servo(6, 1520, -30 * DEG),
                           "dr": Servo(7, 1505)}, Throttle(8, 1100, 1900))
    path = write_ulog(flight, tmp_path / "params.ulg", servos=servos)
    params = ULog(str(path)).initial_parameters  # pyulog reads what PX4 would log
    assert params["PWM_MAIN_FUNC6"] == 202 and params["CA_SV_CS1_TYPE"] == 3  # elevator
    assert params["PWM_MAIN_FUNC8"] == 101 and params["PWM_MAIN_REV"] == 1 << 5
    back, given = read_ulog(path), read_ulog(path, servos)
    # the trims go through float32 CA_SV_CS{i}_TRIM: under 1e-6 us, 1e-9 rad
    for name in ("da", "de", "dr", "throttle"):
        np.testing.assert_allclose(back[name], given[name], rtol=0, atol=1e-8)
    assert back.meta.extra["ulog"]["servos"]["de"]["channel"] == 6
    assert any("30 deg assumed" in n for n in back.meta.extra["ulog"]["notes"])
