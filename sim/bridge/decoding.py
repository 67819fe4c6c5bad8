"""The ground side's inverse of ``bridge.messages``: received MAVLink messages to channels.

:func:`decode` turns a message into canonical channels (SI) by the field conventions of
``bridge.messages``; :data:`CHANNEL_SOURCES` says which messages carry each channel, best
first; :func:`message_time` reads a message's time stamp and :func:`resolution` the
quantisation step of a channel as a message carries it.
"""

from __future__ import annotations

import numpy as np

from flightid.sim.bridge.messages import _IMU_BITS, ServoMap, quaternion_to_euler
from flightid.units import DEG, G0

#: for each canonical channel, the (message, field) pairs that carry it, best first
CHANNEL_SOURCES: dict[str, tuple[str, ...]] = {
    "ax": ("HIGHRES_IMU", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "ay": ("HIGHRES_IMU", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "az": ("HIGHRES_IMU", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "p": ("HIGHRES_IMU", "ATTITUDE", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "q": ("HIGHRES_IMU", "ATTITUDE", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "r": ("HIGHRES_IMU", "ATTITUDE", "HIL_SENSOR", "HIL_STATE_QUATERNION"),
    "p_static": ("HIGHRES_IMU", "HIL_SENSOR"),
    "qbar": ("HIGHRES_IMU", "HIL_SENSOR"),
    "h": ("HIGHRES_IMU", "HIL_SENSOR", "VFR_HUD", "HIL_STATE_QUATERNION", "GPS_RAW_INT"),
    "phi": ("ATTITUDE", "HIL_STATE_QUATERNION"),
    "theta": ("ATTITUDE", "HIL_STATE_QUATERNION"),
    "psi": ("ATTITUDE", "HIL_STATE_QUATERNION"),
    "alpha": ("AOA_SSA",),
    "beta": ("AOA_SSA",),
    "V": ("VFR_HUD", "HIL_STATE_QUATERNION"),
    "de": ("SERVO_OUTPUT_RAW",),
    "da": ("SERVO_OUTPUT_RAW",),
    "dr": ("SERVO_OUTPUT_RAW",),
    "throttle": ("SERVO_OUTPUT_RAW",),
    "latitude": ("GPS_RAW_INT", "HIL_STATE_QUATERNION"),
    "longitude": ("GPS_RAW_INT", "HIL_STATE_QUATERNION"),
}


def message_time(msg) -> float | None:
    """Time stamp carried by a message, or None if it has none.

    Parameters
    ----------
    msg : pymavlink message
        A received message.

    Returns
    -------
    float or None
        Time stamp, s, on the sender's clock (``time_usec`` or ``time_boot_ms``).
    """
    if hasattr(msg, "time_usec"):
        return msg.time_usec * 1e-6
    if hasattr(msg, "time_boot_ms"):
        return msg.time_boot_ms * 1e-3
    return None


def _imu_fields(msg, out: dict[str, float]) -> None:
    vals = {
        "ax": msg.xacc, "ay": msg.yacc, "az": msg.zacc,
        "p": msg.xgyro, "q": msg.ygyro, "r": msg.zgyro,
        "p_static": msg.abs_pressure * 100.0, "qbar": msg.diff_pressure * 100.0,
        "h": msg.pressure_alt,
    }
    for k, v in vals.items():
        if msg.fields_updated & (1 << _IMU_BITS[k]):
            out[k] = v


def decode(msg, servo_map: ServoMap) -> dict[str, float]:
    """Canonical channels (SI) carried by a received message; unknown fields are left out.

    Parameters
    ----------
    msg : pymavlink message
        A received message.
    servo_map : ServoMap
        Maps servo outputs (PWM) back to surface deflections.

    Returns
    -------
    dict of str to float
        Finite channel values by name, SI (rad, rad/s, m, m/s, m/s^2, Pa).
    """
    kind = msg.get_type()
    out: dict[str, float] = {}
    if kind in ("HIGHRES_IMU", "HIL_SENSOR"):
        _imu_fields(msg, out)
    elif kind == "ATTITUDE":
        out.update(phi=msg.roll, theta=msg.pitch, psi=msg.yaw,
                   p=msg.rollspeed, q=msg.pitchspeed, r=msg.yawspeed)
    elif kind == "AOA_SSA":
        out.update(alpha=msg.AOA * DEG, beta=msg.SSA * DEG)
    elif kind == "VFR_HUD":
        # throttle is not decoded here: an integer 0 cannot say "unknown"
        out.update(V=msg.airspeed, h=msg.alt)
    elif kind == "SERVO_OUTPUT_RAW":
        for ch, num in servo_map.channels().items():
            out[ch] = servo_map.from_pwm(ch, getattr(msg, f"servo{num}_raw"))
    elif kind == "GPS_RAW_INT":
        if msg.fix_type >= 2:
            out.update(latitude=msg.lat * 1e-7 * DEG, longitude=msg.lon * 1e-7 * DEG,
                       h=msg.alt * 1e-3)
    elif kind == "HIL_STATE_QUATERNION":
        phi, theta, psi = quaternion_to_euler(tuple(msg.attitude_quaternion))
        out.update(
            phi=phi, theta=theta, psi=psi, p=msg.rollspeed, q=msg.pitchspeed, r=msg.yawspeed,
            latitude=msg.lat * 1e-7 * DEG, longitude=msg.lon * 1e-7 * DEG, h=msg.alt * 1e-3,
            V=msg.true_airspeed / 100.0,
            ax=msg.xacc * 1e-3 * G0, ay=msg.yacc * 1e-3 * G0, az=msg.zacc * 1e-3 * G0,
        )
    return {k: float(v) for k, v in out.items() if v is not None and np.isfinite(v)}


def resolution(channel: str, message: str, value: float, servo_map: ServoMap) -> float:
    """Quantisation step of a channel as carried by a message, near ``value`` (SI).

    float32 fields: one unit in the last place; integer fields: their scale.

    Parameters
    ----------
    channel : str
        Canonical channel name.
    message : str
        Message name carrying it.
    value : float
        Value near which the step is taken, SI.
    servo_map : ServoMap
        Gives the step of a surface carried as PWM.

    Returns
    -------
    float
        The step, in the channel's SI unit.
    """
    f32 = float(np.spacing(np.float32(abs(value) if np.isfinite(value) else 1.0)))
    if message == "SERVO_OUTPUT_RAW":
        return servo_map.resolution(channel)
    if message == "GPS_RAW_INT":
        return 1e-3 if channel == "h" else 1e-7 * DEG
    if message == "HIL_STATE_QUATERNION":
        steps = {"latitude": 1e-7 * DEG, "longitude": 1e-7 * DEG, "h": 1e-3, "V": 0.01,
                 "ax": 1e-3 * G0, "ay": 1e-3 * G0, "az": 1e-3 * G0}
        # angles go through float32 quaternion components of size <= 1
        return steps.get(channel, 4 * float(np.spacing(np.float32(1.0))))
    if message in ("HIGHRES_IMU", "HIL_SENSOR") and channel in ("p_static", "qbar"):
        return 100.0 * float(np.spacing(np.float32(abs(value) / 100.0)))
    if message == "AOA_SSA":
        return DEG * float(np.spacing(np.float32(abs(value) / DEG)))
    return f32
