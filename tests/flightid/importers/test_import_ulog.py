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
from flightid.importers.ulog import read_ulog, servos_from_params
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
def flown():
    return fly("telemaster-id", seed=1)


@pytest.fixture(scope="module")
def flight(flown):
    return flown.truth_record


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
    out = tmp_path / "x.parquet"
    result = CliRunner().invoke(app, ["import", str(path), "-o", str(out)])
    assert result.exit_code == 2 and "vehicle_attitude, actuator_outputs or " \
        "actuator_servos" in result.output
    assert "Traceback" not in result.output and not out.exists()


def test_without_a_mapping_the_logs_px4_parameters_give_outputs_and_trims(flight, tmp_path):
    # outputs off ArduPlane's order, offset trims, a reversed elevator, a 1100-1900 us
    # throttle; throws of 30 deg, the value assumed without a mapping
    servos = ServoMapping({"da": Servo(5, 1490), "de": Servo(6, 1520, -30 * DEG),
                           "dr": Servo(7, 1505)}, Throttle(8, 1100, 1900))
    path = write_ulog(flight, tmp_path / "params.ulg", servos=servos)
    params = ULog(str(path)).initial_parameters  # pyulog reads what PX4 would log
    assert params["PWM_MAIN_FUNC6"] == 202 and params["CA_SV_CS1_TYPE"] == 3  # elevator
    # PX4's positive values give positive moments, flightid's deflections negative ones:
    # the elevator's -30 deg throw is an output as PX4 drives it, the rudder's +30 deg a
    # reversed one, the left aileron's +30 deg (its roll torque is negative) not reversed
    assert params["CA_SV_CS1_TRQ_P"] == 1.0 and params["CA_SV_CS0_TRQ_R"] == -0.5
    assert params["PWM_MAIN_FUNC8"] == 101 and params["PWM_MAIN_REV"] == 1 << 6
    back, given = read_ulog(path), read_ulog(path, servos)
    # the trims go through float32 CA_SV_CS{i}_TRIM: under 1e-6 us, 1e-9 rad
    for name in ("da", "de", "dr", "throttle"):
        np.testing.assert_allclose(back[name], given[name], rtol=0, atol=1e-8)
    assert back.meta.extra["ulog"]["servos"]["de"]["channel"] == 6
    assert any("30 deg assumed" in n for n in back.meta.extra["ulog"]["notes"])


@pytest.mark.parametrize("kind, roll", [(1, -1.0), (2, 1.0)])
def test_an_aileron_value_rolls_as_its_px4_torque_says(flown, kind, roll):
    """PX4's left aileron has a roll torque of -0.5, its right aileron +0.5 (a positive
    value rolls right). A value of +0.2 on an output not reversed (1600 us) read as da
    and put through the Telemaster's Cl_da (flightid's sign, < 0) rolls the same way; at
    the assumed 30 deg throw it is 6 deg. A logged torque parameter overrides the type's."""
    notes: list[str] = []
    servos = servos_from_params({"PWM_MAIN_FUNC1": 201, "CA_SV_CS0_TYPE": kind}, notes)
    da = servos.surfaces["da"].deflection(1600.0)
    assert da == pytest.approx(-roll * 6 * DEG)
    assert np.sign(flown.truth["Cl_da"] * da) == roll
    turned = servos_from_params({"PWM_MAIN_FUNC1": 201, "CA_SV_CS0_TYPE": kind,
                                 "CA_SV_CS0_TRQ_R": 0.5 * roll * -1}, [])
    assert turned.surfaces["da"].deflection(1600.0) == pytest.approx(roll * 6 * DEG)
    assert (kind == 2) == any("right aileron" in n for n in notes)


def test_a_right_aileron_logged_through_actuator_servos_reads_as_the_flight(flight, tmp_path):
    """No PWM logged: actuator_servos' values (trims included, before the output's
    reversal) of a right aileron, a reversed elevator and a rudder on outputs 5-7, read
    with the log's parameters, give the surfaces read from the PWM of the same flight with
    the mapping given, within the PWM's half microsecond (throw / 1000), and the flight
    within float32."""
    servos = ServoMapping({"da": Servo(5, 1490, -30 * DEG), "de": Servo(6, 1520, 30 * DEG),
                           "dr": Servo(7, 1505, -30 * DEG)}, Throttle(8, 1100, 1900))
    rates = {"actuator_outputs": 0, "actuator_servos": RATES["actuator_outputs"]}
    path = write_ulog(flight, tmp_path / "servos.ulg", servos=servos, right_aileron=True,
                      rates=rates)
    params = ULog(str(path)).initial_parameters
    assert params["CA_SV_CS0_TYPE"] == 2 and params["CA_SV_CS0_TRQ_R"] == 0.5
    assert params["PWM_MAIN_REV"] == 1 << 5  # only the elevator turned over
    back = read_ulog(path)
    pwm = read_ulog(write_ulog(flight, tmp_path / "pwm.ulg", servos=servos), servos)
    assert back.meta.extra["ulog"]["commands_from"] == "actuator_servos"
    notes = back.meta.extra["ulog"]["notes"]
    assert any("right aileron" in n for n in notes) and any("throttle not read" in n
                                                             for n in notes)
    t = back.time - BOOT_S + flight.time[0]
    times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9, 1 / rates[
        "actuator_servos"])
    for name in ("da", "de", "dr"):
        worst = np.max(np.abs(back[name] - pwm[name]))
        assert worst <= 30 * DEG / 1000 + 1e-6, (name, worst)  # measured 5.0e-4
        # float32 values of at most 1: 2^-24 of the 30 deg throw (measured 4.2e-9 rad)
        expected = np.interp(t, times, np.interp(times, flight.time, flight[name]))
        worst = np.max(np.abs(back[name] - expected))
        assert worst <= 2 * F32 * 30 * DEG, (name, worst)
    assert np.ptp(back["da"]) > 0.9 * np.ptp(flight["da"])  # the aileron moved: 2 deg


def test_without_vehicle_angular_velocity_the_rates_come_from_sensor_combined(log, flight,
                                                                              tmp_path):
    path = write_ulog(flight, tmp_path / "gyro.ulg", servos=SERVOS,
                      rates={"vehicle_angular_velocity": 0})
    back, whole = read_ulog(path, SERVOS), read_ulog(log, SERVOS)
    assert back.dt == pytest.approx(1 / RATES["sensor_combined"])
    for name in ("p", "q", "r"):  # the same float32 rates at the same 100 Hz
        np.testing.assert_array_equal(back[name], whole[name])


def test_a_left_and_a_right_aileron_give_the_mean_of_their_deflections(flight, tmp_path):
    """Two aileron servos, left on output 5 and right on output 9, each as PX4 drives it
    (not reversed: the right one's throw is negative in flightid's sign), the right one
    with an offset trim. Read with the log's parameters, da is the mean of the two
    deflections: the flight's within the PWM's half microsecond (throw / 1000)."""
    servos = ServoMapping({"da": Servo(5, 1490), "de": Servo(6, 1520, -30 * DEG),
                           "dr": Servo(7, 1505, -30 * DEG)}, Throttle(8, 1100, 1900),
                          partners={"da": Servo(9, 1530, -30 * DEG)})
    path = write_ulog(flight, tmp_path / "two.ulg", servos=servos)
    params = ULog(str(path)).initial_parameters
    types = {params[f"CA_SV_CS{i}_TYPE"] for i in range(int(params["CA_SV_CS_COUNT"]))}
    assert types == {1, 2, 3, 4} and params["PWM_MAIN_REV"] == 0
    back = read_ulog(path)
    assert any("mean of the left and the right aileron" in n
               for n in back.meta.extra["ulog"]["notes"])
    t = back.time - BOOT_S + flight.time[0]
    times = flight.time[0] + np.arange(0, t[-1] - flight.time[0] + 1e-9,
                                       1 / RATES["actuator_outputs"])
    expected = np.interp(t, times, np.interp(times, flight.time, flight["da"]))
    assert np.max(np.abs(back["da"] - expected)) <= 30 * DEG / 1000 * (1 + 1e-9)
