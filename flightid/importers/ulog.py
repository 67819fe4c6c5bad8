"""PX4 ULog files (``.ulg``) into a FlightRecord, read with pyulog.

Topics used (``ulog_topics``):

* ``vehicle_angular_velocity`` (else ``sensor_combined``'s gyro): p, q, r (rad/s);
  ``sensor_combined``: specific force ax, ay, az (m/s^2);
* ``vehicle_attitude``: the quaternion (body FRD to NED), as phi, theta, psi (rad);
* ``airspeed``: true airspeed V (m/s); ``differential_pressure``: qbar (Pa);
* ``actuator_outputs`` (instance 0): servo outputs (PWM, us) mapped to de, da, dr and
  throttle through a :class:`~flightid.importers.servos.ServoMapping`; without it,
  ``actuator_servos``' values (-1..1, trims included) give the surfaces as the PWM PX4
  puts out for them (:func:`servo_pwm`; the servo of an output from PWM_MAIN_FUNCn).
  These are COMMANDS (``meta.extra['surfaces'] = 'command'``);
* ``airflow_aoa``, ``airflow_slip`` (vanes), ``vehicle_air_data`` (h, static pressure,
  density), ``vehicle_global_position`` (latitude, longitude) when logged.

Every topic is stamped in microseconds since boot on one clock; each channel is
interpolated linearly from its own times onto one uniform grid at the rate of the rate
topic (or a given rate), over the span the needed topics share. Other topics, other
instances, parameters and log texts are not kept. A file cut in the middle of a message
keeps every whole message before the cut and says how many bytes were dropped; one that
pyulog finds damaged keeps what pyulog could read and says so.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from pyulog import ULog

from flightid.console import captured_output
from flightid.flight_record import FlightRecord, RecordMeta, check_samples
from flightid.importers.dataflash import DEFAULT_THROW
from flightid.importers.servos import Servo, ServoMapping, Throttle
from flightid.importers.ulog_topics import (
    PX4_DEFAULT_TORQUE,
    PX4_MOTOR_FUNCTION,
    PX4_OUTPUTS,
    PX4_RIGHT_AILERON,
    PX4_SERVO_FUNCTION,
    PX4_SURFACE_TYPES,
    PX4_TORQUE_AXIS,
    TOPICS,
)

REQUIRED = ("vehicle_attitude", "sensor_combined", "airspeed")
COMMANDS = ("actuator_outputs", "actuator_servos")  # one of them
CONDITION_CHANNELS = ("V", "h", "alpha", "beta", "qbar", "rho", "mass")


def euler_from_quaternion(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """phi, theta, psi (ZYX Euler angles) of unit quaternions rotating body axes to NED.

    Stevens, Lewis & Johnson 2016, sec. 1.8.

    Parameters
    ----------
    q : numpy.ndarray
        Unit quaternions (w, x, y, z); shape (n, 4).

    Returns
    -------
    tuple of numpy.ndarray
        (phi, theta, psi), rad; each shape (n,).
    """
    w, x, y, z = (q[:, i] for i in range(4))
    phi = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    theta = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    psi = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return phi, theta, psi


def servos_from_params(params: dict[str, float], notes: list[str]) -> ServoMapping | None:
    """The servo mapping PX4's control allocation parameters give (``ulog_topics``:
    PWM_MAIN_FUNCn, CA_SV_CS{i}_TYPE, _TRIM and _TRQ_R/P/Y, PWM_MAIN_MINn, _MAXn,
    PWM_MAIN_REV), with the throws :data:`~flightid.importers.dataflash.DEFAULT_THROW`;
    None when no output is a control surface or motor 1. What is assumed or not read goes
    to ``notes``.

    Parameters
    ----------
    params : the log's parameters, name -> value.
    notes : list the notes are appended to.

    Returns
    -------
    ServoMapping, or None. A surface's throw has the sign of flightid's deflection for a
    positive actuator value (``ulog_topics.PX4_DEFAULT_TORQUE``): opposite to its torque
    parameter (else its type's default torque), reversed again on a reversed output.
    """
    reversed_mask = int(params.get("PWM_MAIN_REV", 0))
    surfaces: dict[str, Servo] = {}
    throttle = None
    right_aileron = None
    for n in range(1, PX4_OUTPUTS + 1):
        function = int(params.get(f"PWM_MAIN_FUNC{n}", 0))
        low = float(params.get(f"PWM_MAIN_MIN{n}", 1000.0))
        high = float(params.get(f"PWM_MAIN_MAX{n}", 2000.0))
        reverse = bool(reversed_mask >> (n - 1) & 1)
        if function == PX4_MOTOR_FUNCTION:
            throttle = Throttle(n, high, low) if reverse else Throttle(n, low, high)
            continue
        index = function - PX4_SERVO_FUNCTION
        if not 0 <= index < PX4_OUTPUTS:
            continue
        kind = int(params.get(f"CA_SV_CS{index}_TYPE", 0))
        if kind not in PX4_SURFACE_TYPES:
            continue
        name = PX4_SURFACE_TYPES[kind]
        torque = float(params.get(f"CA_SV_CS{index}_TRQ_{PX4_TORQUE_AXIS[name]}", 0.0)) or \
            PX4_DEFAULT_TORQUE[kind]
        trim = (low + high) / 2 + float(params.get(f"CA_SV_CS{index}_TRIM", 0.0)) * \
            (high - low) / 2
        sign = -np.sign(torque) * (-1.0 if reverse else 1.0)
        servo = Servo(n, trim, sign * DEFAULT_THROW)
        if kind == PX4_RIGHT_AILERON:
            right_aileron = right_aileron or servo
        elif name not in surfaces:
            surfaces[name] = servo
    partners = {}
    if "da" not in surfaces and right_aileron is not None:
        surfaces["da"] = right_aileron
        notes.append("da is the right aileron's output (no left aileron is set), its sign "
                     "turned to flightid's (a right aileron's positive value rolls right)")
    elif right_aileron is not None:
        partners["da"] = right_aileron
        notes.append("da is the mean of the left and the right aileron's deflections (the "
                     "right one's sign turned to flightid's)")
    if not surfaces and throttle is None:
        return None
    notes.append("servo outputs, trims, reversals and throttle range from the log's PX4 "
                 f"parameters (PWM_MAIN_*, CA_SV_CS*); throws are in no parameter: "
                 f"{DEFAULT_THROW / np.pi * 180:g} deg assumed (give a servo mapping for the "
                 "real ones)")
    return ServoMapping(surfaces, throttle, partners)


def _topics(path: Path) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, int], list[str],
                                 dict[str, float]]:
    with captured_output():
        try:
            log = ULog(str(path), list(TOPICS))
        except Exception as exc:  # pyulog raises assorted types on a foreign file
            raise ValueError(f"{path}: not a readable ULog file ({type(exc).__name__}: "
                             f"{exc})") from None
    topics, counts, notes = {}, {}, []
    for data in log.data_list:
        counts[f"{data.name}/{data.multi_id}"] = len(data.data["timestamp"])
        if data.multi_id == 0:
            topics[data.name] = {k: np.asarray(v, dtype=float) for k, v in data.data.items()}
        else:
            notes.append(f"{data.name} instance {data.multi_id} not kept")
    if log.file_corruption:
        notes.append("pyulog found the file damaged: the whole messages it could read are "
                     "kept, the damaged ones dropped")
    cut = cut_bytes(path)
    if cut:
        notes.append(f"the file ends in a cut message: {cut} byte(s) after the last whole "
                     "message dropped")
    params = {str(k): float(v) for k, v in log.initial_parameters.items()
              if isinstance(v, int | float)}
    return topics, counts, notes, params


HEADER_BYTES = 16  # ULog file header: magic, version, timestamp
MESSAGE_HEADER = 3  # uint16 size, uint8 type


def cut_bytes(path: Path) -> int:
    """Bytes at the end of a ULog file that do not make a whole message.

    The messages' own sizes are walked from the file header on.

    Parameters
    ----------
    path : pathlib.Path
        The .ulg file.

    Returns
    -------
    int
        Number of trailing bytes; 0 for a whole file.
    """
    data = path.read_bytes()
    offset = HEADER_BYTES
    while offset + MESSAGE_HEADER <= len(data):
        size = int.from_bytes(data[offset:offset + 2], "little")
        if offset + MESSAGE_HEADER + size > len(data):
            break
        offset += MESSAGE_HEADER + size
    return max(len(data) - offset, 0)


def _vector(topic: dict[str, np.ndarray], name: str, n: int) -> np.ndarray:
    return np.column_stack([topic[f"{name}[{i}]"] for i in range(n)])


def read_ulog(path: str | Path, servos: ServoMapping | None = None,
              rate: float | None = None) -> FlightRecord:
    """Read a PX4 ULog file into a FlightRecord in SI units (module docstring).

    Parameters
    ----------
    path : the ``.ulg`` file.
    servos : servo outputs to surfaces (actuator_outputs index = channel; default: the
        log's PX4 output parameters with 30 deg throws (:func:`servos_from_params`), else
        ArduPlane's order with 30 deg throws, as for DataFlash).
    rate : output rate (Hz); default the rate topic's (vehicle_angular_velocity, else
        sensor_combined).

    Returns
    -------
    FlightRecord with time in s since boot, ``meta.extra['surfaces'] = 'command'`` and
    ``meta.extra['ulog']`` (topic counts, rate, servo mapping, notes).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    topics, counts, notes, params = _topics(path)
    if servos is None:
        servos = servos_from_params(params, notes)
    if servos is None:
        servos = ServoMapping()
        notes.append("no servo mapping given and no PX4 output parameter in the log: "
                     "ArduPlane's output order (1 aileron, 2 elevator, 3 throttle, 4 rudder) "
                     "with 1500 us trims and 30 deg throws assumed")
    missing = [k for k in REQUIRED if k not in topics]
    if not any(k in topics for k in COMMANDS):
        missing.append(" or ".join(COMMANDS))
    if missing:
        present = ", ".join(sorted({k.split("/")[0] for k in counts})) or "none"
        raise ValueError(f"{path}: the log lacks the topic(s) {', '.join(missing)} that a "
                         f"flight record needs; it has: {present}")
    t = {k: v["timestamp"] * 1e-6 for k, v in topics.items()}
    rates_topic = "vehicle_angular_velocity" if "vehicle_angular_velocity" in topics \
        else "sensor_combined"
    step = 1.0 / rate if rate else float(np.median(np.diff(t[rates_topic])))
    command = "actuator_outputs" if "actuator_outputs" in topics else "actuator_servos"
    used = [*REQUIRED, rates_topic, command]
    lo, hi = max(t[k][0] for k in used), min(t[k][-1] for k in used)
    n = int(np.floor((hi - lo) / step + 1e-6)) + 1
    if n < 2:
        raise ValueError(f"{path}: the topics {', '.join(used)} share less than two samples "
                         f"of time ({lo:.3f} to {hi:.3f} s)")
    grid = lo + step * np.arange(n)

    def at(topic: str, values: np.ndarray) -> np.ndarray:
        return np.interp(grid, t[topic], values)

    rates = _vector(topics[rates_topic], "xyz" if rates_topic != "sensor_combined"
                    else "gyro_rad", 3)
    acc = _vector(topics["sensor_combined"], "accelerometer_m_s2", 3)
    ch: dict[str, np.ndarray] = {name: at(rates_topic, rates[:, i]) for i, name in
                                 enumerate(("p", "q", "r"))}
    ch.update({name: at("sensor_combined", acc[:, i]) for i, name in
               enumerate(("ax", "ay", "az"))})
    phi, theta, psi = euler_from_quaternion(_vector(topics["vehicle_attitude"], "q", 4))
    ch["phi"], ch["theta"] = at("vehicle_attitude", phi), at("vehicle_attitude", theta)
    psi = np.unwrap(psi)
    ch["psi"] = at("vehicle_attitude", psi - 2 * np.pi * np.round(psi[0] / (2 * np.pi)))
    ch["V"] = at("airspeed", topics["airspeed"]["true_airspeed_m_s"])
    optional = {"differential_pressure": ("differential_pressure_pa", "qbar"),
                "airflow_aoa": ("aoa_rad", "alpha"), "airflow_slip": ("slip_rad", "beta")}
    for topic, (field, name) in optional.items():
        if topic in topics:
            ch[name] = at(topic, topics[topic][field])
    if "vehicle_air_data" in topics:
        air = topics["vehicle_air_data"]
        ch["h"] = at("vehicle_air_data", air["baro_alt_meter"])
        ch["p_static"] = at("vehicle_air_data", air["baro_pressure_pa"])
        ch["rho"] = at("vehicle_air_data", air["rho"])
    if "vehicle_global_position" in topics:
        pos = topics["vehicle_global_position"]
        ch["latitude"] = at("vehicle_global_position", np.radians(pos["lat"]))
        ch["longitude"] = at("vehicle_global_position", np.radians(pos["lon"]))
    ch.update(_commands(path, topics[command], command, grid, t[command], servos, notes,
                        params))
    check_samples(str(path), grid, ch)
    condition: dict[str, Any] = {k: float(np.mean(ch[k])) for k in CONDITION_CHANNELS
                                 if k in ch}
    condition["note"] = "means over the record (SI units), the reference of perturbation models"
    extra = {"surfaces": "command",
             "ulog": {"file": path.name, "counts": counts, "rate_hz": 1.0 / step,
                      "span_s": [float(lo), float(hi)], "servos": servos.as_dict(),
                      "commands_from": command, "notes": notes,
                      "time": "s since boot (timestamp); every channel interpolated "
                              "linearly from its own topic's times onto this grid"}}
    meta = RecordMeta(condition=condition, sample_rate=1.0 / step, extra=extra,
                      provenance=f"PX4 ULog file {path.name} read by "
                                 "flightid.importers.ulog (pyulog)")
    return FlightRecord(grid, ch, meta)


def _commands(path: Path, topic: dict[str, np.ndarray], name: str, grid: np.ndarray,
              t: np.ndarray, servos: ServoMapping, notes: list[str],
              params: dict[str, float]) -> dict[str, np.ndarray]:
    out = {}
    width = 16 if name == "actuator_outputs" else 8
    for channel, output in servos.outputs().items():
        if name == "actuator_outputs":
            if output > width:
                raise ValueError(f"{path}: {name} has {width} outputs; {channel} is mapped "
                                 f"to output {output}")
            values = topic[f"output[{output - 1}]"]
        elif channel == "throttle":
            notes.append("throttle not read: actuator_servos carries the servos only")
            continue
        else:
            index = servo_index(params, output)
            if not 0 <= index < width:
                raise ValueError(f"{path}: {name} has {width} servos; {channel} is on output "
                                 f"{output}, servo {index + 1}")
            values = servo_pwm(topic[f"control[{index}]"], output, params)
        if channel == "throttle":
            out[channel] = np.interp(grid, t, servos.throttle.value(values))
            continue
        if not np.any(np.isfinite(values) & (values != 0)):
            raise ValueError(f"{path}: {name} output {output} (mapped to {channel}) is never "
                             "set: the output is not in use; fix the servo mapping")
        out[channel] = np.interp(grid, t, servos.surfaces[channel].deflection(values))
    for channel, servo in servos.partners.items():
        if name == "actuator_outputs":
            if servo.channel > width:
                raise ValueError(f"{path}: {name} has {width} outputs; {channel}'s second "
                                 f"servo is mapped to output {servo.channel}")
            values = topic[f"output[{servo.channel - 1}]"]
        else:
            values = servo_pwm(topic[f"control[{servo_index(params, servo.channel)}]"],
                               servo.channel, params)
        out[channel] = 0.5 * (out[channel] + np.interp(grid, t, servo.deflection(values)))
    return out


def servo_index(params: dict[str, float], output: int) -> int:
    """The servo (0-based, actuator_servos' control index) on PWM output ``output``
    (1-based): PWM_MAIN_FUNCn - 201, else output - 1 when the log has no such parameter.

    Parameters
    ----------
    params : the log's parameters.
    output : PWM output number, 1-based.

    Returns
    -------
    The control index, 0-based.
    """
    return int(params.get(f"PWM_MAIN_FUNC{output}", PX4_SERVO_FUNCTION + output - 1)) - \
        PX4_SERVO_FUNCTION


def servo_pwm(control: np.ndarray, output: int, params: dict[str, float]) -> np.ndarray:
    """The PWM (us) PX4 puts out for actuator_servos' values (-1..1, the servo trims
    CA_SV_CS{i}_TRIM included) on output ``output``: the middle of PWM_MAIN_MINn..MAXn
    (default 1000..2000 us) plus the value times the half range, turned over on a
    reversed output (PWM_MAIN_REV).

    Parameters
    ----------
    control : actuator_servos values, -1..1.
    output : PWM output number, 1-based.
    params : the log's parameters.

    Returns
    -------
    PWM values (us), unrounded.
    """
    low = float(params.get(f"PWM_MAIN_MIN{output}", 1000.0))
    high = float(params.get(f"PWM_MAIN_MAX{output}", 2000.0))
    sign = -1.0 if int(params.get("PWM_MAIN_REV", 0)) >> (output - 1) & 1 else 1.0
    return (low + high) / 2 + sign * np.asarray(control, dtype=float) * (high - low) / 2
