"""The recorder bridge writes a flight as a PX4 ULog file (``.ulg``): the ULog format
(file header, flag bits, formats, info, subscriptions, data messages; PX4's "ULog File
Format" specification) with PX4's uORB topic names and fields
(``flightid.importers.ulog_topics``), each topic at its own rate on the microsecond clock
since boot. pyulog (not this writer) is what reads the files back.

Rates (Hz), chosen here for a fixed-wing identification log (PX4's logger profiles vary):
sensor_combined and vehicle_angular_velocity 100, vehicle_attitude 50, actuator_outputs
50, airspeed, differential_pressure, airflow_aoa, airflow_slip and vehicle_air_data 20,
vehicle_global_position 10; actuator_servos (PX4's values behind the PWM of the servo
outputs) only when given a rate.

What the logging does to the values: every float field is float32 (24 bits of mantissa;
the attitude goes through a float32 quaternion), the servo outputs are whole
microseconds of PWM, latitude and longitude are float64 degrees.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from flightid.atmosphere import isa, isa_density
from flightid.files import atomic_path
from flightid.importers.servos import HALF_RANGE_US, ServoMapping
from flightid.importers.ulog import servo_index
from flightid.importers.ulog_topics import (
    PX4_DEFAULT_TORQUE,
    PX4_MOTOR_FUNCTION,
    PX4_RIGHT_AILERON,
    PX4_SERVO_FUNCTION,
    PX4_TORQUE_AXIS,
    TOPICS,
)
from flightid.record import FlightRecord
from flightid.sim.bridge.air.dataflash import BOOT_S, message_times, sampled
from flightid.units import DEG

MAGIC = b"ULog\x01\x12\x35"
VERSION = 1
RATES: dict[str, float] = {
    "sensor_combined": 100.0, "vehicle_angular_velocity": 100.0, "vehicle_attitude": 50.0,
    "actuator_outputs": 50.0, "airspeed": 20.0, "differential_pressure": 20.0,
    "airflow_aoa": 20.0, "airflow_slip": 20.0, "vehicle_air_data": 20.0,
    "vehicle_global_position": 10.0, "actuator_servos": 0.0,
}
_CODES = {"uint64_t": "Q", "int64_t": "q", "uint32_t": "I", "int32_t": "i", "uint16_t": "H",
          "int16_t": "h", "uint8_t": "B", "int8_t": "b", "float": "f", "double": "d",
          "bool": "?"}


def _message(kind: str, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _layout(topic: str) -> struct.Struct:
    codes = ""
    for kind, _ in TOPICS[topic]:
        base, _, size = kind.partition("[")
        codes += _CODES[base] * (int(size[:-1]) if size else 1)
    return struct.Struct("<" + codes)


def quaternion_from_euler(phi: np.ndarray, theta: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Unit quaternions of ZYX Euler angles, rotating body axes to NED.

    Stevens, Lewis & Johnson 2016, sec. 1.8.

    Parameters
    ----------
    phi, theta, psi : numpy.ndarray
        Roll, pitch and yaw angles, rad; each shape (n,).

    Returns
    -------
    numpy.ndarray
        Quaternions (w, x, y, z); shape (n, 4).
    """
    cr, sr = np.cos(phi / 2), np.sin(phi / 2)
    cp, sp = np.cos(theta / 2), np.sin(theta / 2)
    cy, sy = np.cos(psi / 2), np.sin(psi / 2)
    return np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def px4_params(servos: ServoMapping, *, right_aileron: bool = False) -> dict[str, int | float]:
    """PX4's output parameters for ``servos`` (``ulog_topics``).

    Parameters
    ----------
    servos : surfaces and throttle to outputs.
    right_aileron : log the aileron's output as a right aileron (CA_SV_CS type 2) rather
        than a left one (type 1).

    Returns
    -------
    Parameter name -> value: each surface a control surface of its type on its output,
    over 1000-2000 us, with its type's torque (CA_SV_CS{i}_TRQ_R/P/Y) and its trim as
    CA_SV_CS{i}_TRIM; an output is reversed where the servo's throw has the sign opposite
    to flightid's deflection for a positive actuator value (``ulog_topics``); the throttle
    is motor 1 over its low and high. (The throws themselves are in no PX4 parameter.)
    """
    types = {"da": PX4_RIGHT_AILERON if right_aileron else 1, "de": 3, "dr": 4}
    params: dict[str, int | float] = {}
    reversed_mask = 0
    # a surface's second servo (ServoMapping.partners): the right aileron
    surfaces = sorted([*((name, servo, types.get(name, 0)) for name, servo in
                         servos.surfaces.items()),
                       *((name, servo, PX4_RIGHT_AILERON) for name, servo in
                         servos.partners.items())], key=lambda item: item[1].channel)
    for index, (name, servo, kind) in enumerate(surfaces):
        n = servo.channel
        params[f"CA_SV_CS{index}_TYPE"] = kind
        params[f"CA_SV_CS{index}_TRIM"] = (servo.trim - 1500.0) / HALF_RANGE_US
        params[f"PWM_MAIN_FUNC{n}"] = PX4_SERVO_FUNCTION + index
        params[f"PWM_MAIN_MIN{n}"], params[f"PWM_MAIN_MAX{n}"] = 1000, 2000
        if kind in PX4_DEFAULT_TORQUE:
            torque = PX4_DEFAULT_TORQUE[kind]
            params[f"CA_SV_CS{index}_TRQ_{PX4_TORQUE_AXIS[name]}"] = torque
            reversed_mask |= (servo.throw * torque > 0) << (n - 1)
    params["CA_SV_CS_COUNT"] = len(surfaces)
    if servos.throttle is not None:
        n, low, high = servos.throttle.channel, servos.throttle.low, servos.throttle.high
        params[f"PWM_MAIN_FUNC{n}"] = PX4_MOTOR_FUNCTION
        params[f"PWM_MAIN_MIN{n}"], params[f"PWM_MAIN_MAX{n}"] = round(min(low, high)), \
            round(max(low, high))
        reversed_mask |= (high < low) << (n - 1)
    params["PWM_MAIN_REV"] = reversed_mask
    return params


def _parameter(key: str, value: int | float) -> bytes:
    name = f"{'float' if isinstance(value, float) else 'int32_t'} {key}".encode()
    packed = struct.pack("<f" if isinstance(value, float) else "<i", value)
    return _message("P", bytes([len(name)]) + name + packed)


def write_ulog(record: FlightRecord, path: str | Path, *, servos: ServoMapping | None = None,
               rates: dict[str, float] | None = None, right_aileron: bool = False) -> Path:
    """Write ``record`` (SI, canonical channels) as a PX4 ULog file.

    Parameters
    ----------
    record : the flight; needs p, q, r, ax, ay, az, phi, theta, psi, V and the controls of
        ``servos``; qbar, alpha, beta, h, latitude, longitude are logged when present.
        The servo outputs (actuator_outputs) carry its ``de da dr throttle``: to log
        commands that differ from the surface positions (ahead of a servo lag), pass
        ``record.with_channels(de=commanded, ...)``; no other message reads them.
    path : the ``.ulg`` file (written atomically).
    servos : surfaces and throttle to actuator outputs (1-based).
    rates : topic -> rate (Hz) over :data:`RATES`; a topic at rate 0 is left out.
    right_aileron : the aileron's output is set up as a right aileron (:func:`px4_params`).

    Returns
    -------
    The path written.
    """
    servos = servos or ServoMapping()
    rates = {**RATES, **(rates or {})}
    need = ["p", "q", "r", "ax", "ay", "az", "phi", "theta", "psi", "V", *servos.outputs()]
    missing = [c for c in need if c not in record]
    if missing:
        raise ValueError(f"record lacks {', '.join(missing)}: a ULog file of it needs "
                         f"{', '.join(need)}")
    optional = {"differential_pressure": "qbar", "airflow_aoa": "alpha",
                "airflow_slip": "beta", "vehicle_air_data": "h",
                "vehicle_global_position": "latitude"}
    topics = [k for k in RATES if rates.get(k, 0) > 0 and
              (k not in optional or optional[k] in record)]

    params = px4_params(servos, right_aileron=right_aileron)

    def rows(topic: str, t: np.ndarray) -> list[tuple]:
        v = {name: sampled(record, t, name) for name in
             ("p", "q", "r", "ax", "ay", "az", "V")}
        n = t.size
        if topic == "sensor_combined":
            return [(v["p"][k], v["q"][k], v["r"][k], 0, 0, v["ax"][k], v["ay"][k],
                     v["az"][k], 0, 0, 0, 0, 0) for k in range(n)]
        if topic == "vehicle_angular_velocity":
            return [(0, v["p"][k], v["q"][k], v["r"][k], 0.0, 0.0, 0.0) for k in range(n)]
        if topic == "vehicle_attitude":
            quat = quaternion_from_euler(*(sampled(record, t, c) for c in
                                           ("phi", "theta", "psi")))
            return [(0, *quat[k], 0.0, 0.0, 0.0, 0.0, 0) for k in range(n)]
        h = sampled(record, t, "h", 0.0)
        rho = sampled(record, t, "rho")
        rho = np.where(np.isfinite(rho), rho, isa_density(h))
        if topic == "airspeed":
            eas = v["V"] * np.sqrt(rho / 1.225)
            return [(0, eas[k], v["V"][k], 15.0, 1.0) for k in range(n)]
        if topic == "differential_pressure":
            qbar = sampled(record, t, "qbar")
            return [(0, 1, qbar[k], 15.0, 0) for k in range(n)]
        if topic in ("airflow_aoa", "airflow_slip"):
            angle = sampled(record, t, "alpha" if topic == "airflow_aoa" else "beta")
            return [(angle[k], True) for k in range(n)]
        if topic == "vehicle_air_data":
            press = sampled(record, t, "p_static")
            press = np.where(np.isfinite(press), press, [isa(x)[0] for x in h])
            return [(0, 1, h[k], 15.0, press[k], rho[k], np.sqrt(1.225 / rho[k]), 0)
                    for k in range(n)]
        if topic == "vehicle_global_position":
            lat = sampled(record, t, "latitude") / DEG
            lon = sampled(record, t, "longitude", 0.0) / DEG
            return [(0, lat[k], lon[k], h[k]) for k in range(n)]
        if topic == "actuator_servos":  # PX4's values behind the PWM (servo_pwm's inverse)
            control = np.zeros((n, 8))
            for name, servo in [*servos.surfaces.items(), *servos.partners.items()]:
                c = servo.channel
                sign = -1.0 if int(params["PWM_MAIN_REV"]) >> (c - 1) & 1 else 1.0
                control[:, servo_index(params, c)] = sign * (
                    servo.pwm(sampled(record, t, name), whole=False) - 1500.0) / HALF_RANGE_US
            return [(0, *control[k]) for k in range(n)]
        # actuator_outputs: whole-microsecond PWM
        pwm = np.zeros((n, 16))
        for name, servo in [*servos.surfaces.items(), *servos.partners.items()]:
            pwm[:, servo.channel - 1] = servo.pwm(sampled(record, t, name))
        if servos.throttle is not None:
            pwm[:, servos.throttle.channel - 1] = servos.throttle.pwm(
                sampled(record, t, "throttle"))
        return [(16, *pwm[k]) for k in range(n)]

    data: list[tuple[int, int, bytes]] = []
    for msg_id, topic in enumerate(topics):
        t = message_times(record, rates[topic])
        us = np.round((t - record.time[0] + BOOT_S) * 1e6).astype(np.int64)
        layout = _layout(topic)
        for k, values in enumerate(rows(topic, t)):
            fields = list(values)
            if topic in ("vehicle_angular_velocity", "vehicle_attitude", "airspeed",
                         "actuator_servos",
                         "differential_pressure", "vehicle_air_data",
                         "vehicle_global_position"):
                fields[0] = int(us[k])  # timestamp_sample
            payload = struct.pack("<H", msg_id) + layout.pack(int(us[k]), *fields)
            data.append((int(us[k]), msg_id, _message("D", payload)))
    data.sort(key=lambda r: (r[0], r[1]))
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        fh.write(MAGIC + bytes([VERSION]) + struct.pack("<Q", round(BOOT_S * 1e6)))
        fh.write(_message("B", bytes(16) + struct.pack("<3Q", 0, 0, 0)))
        for topic in topics:
            fields = "".join(f"{kind} {name};" for kind, name in TOPICS[topic])
            fh.write(_message("F", f"{topic}:{fields}".encode()))
        for key, value in (("sys_name", "flightid bridge"), ("ver_hw", "JSBSIM")):
            name = f"char[{len(value)}] {key}".encode()
            fh.write(_message("I", bytes([len(name)]) + name + value.encode()))
        for key, value in params.items():
            fh.write(_parameter(key, value))
        for msg_id, topic in enumerate(topics):
            fh.write(_message("A", struct.pack("<BH", 0, msg_id) + topic.encode()))
        for _, _, message in data:
            fh.write(message)
    return path
