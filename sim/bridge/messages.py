"""MAVLink 2 encoding of flight-record channels (the inverse: ``bridge.decoding``).

One sample of canonical channels (SI, ``flightid.channels``) becomes the telemetry an
onboard recorder would send (as on the Monash Boomerang 60 UAV, c. 2008: IMU with
pressures and GPS, servo positions), and each received message decodes back to canonical
channels (``bridge.decoding``). Dialect: ardupilotmega (it includes common and AOA_SSA),
MAVLink 2 framing.

Field conventions (MAVLink common.xml units, converted here and in ``bridge.decoding``,
nowhere else):
- HIGHRES_IMU / HIL_SENSOR: specific force (m/s^2), body rates (rad/s), static pressure and
  dynamic pressure (hPa), pressure altitude (m); ``fields_updated`` says which are valid.
- ATTITUDE: phi, theta, psi (psi wrapped to [-pi, pi]), p, q, r.
- AOA_SSA: alpha, beta in deg.
- VFR_HUD: true airspeed (m/s, the field nominally carries IAS/CAS; documented choice),
  heading (integer deg), throttle (integer %), altitude (m), climb rate (m/s).
- SERVO_OUTPUT_RAW: surfaces as PWM, see :class:`ServoMap`.
- GPS_RAW_INT: latitude/longitude (deg * 1e7), altitude MSL (mm), ground speed (cm/s),
  course (cdeg); UINT16_MAX means unknown.
- HIL_STATE_QUATERNION: attitude quaternion (w, x, y, z), rates, position, NED ground
  velocity (cm/s), indicated and true airspeed (cm/s), specific force (mG).
Float fields are float32: missing inputs are sent as NaN (MAVLink's "unknown").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from flightid.atmosphere import RHO0, isa
from flightid.units import DEG, G0

NAN = float("nan")
UINT16_MAX = 65535

#: messages the air side can send, in the order they leave within one tick
TELEMETRY = (
    "HEARTBEAT",
    "SYSTEM_TIME",
    "HIGHRES_IMU",
    "ATTITUDE",
    "AOA_SSA",
    "VFR_HUD",
    "SERVO_OUTPUT_RAW",
    "GPS_RAW_INT",
    "HIL_SENSOR",
    "HIL_STATE_QUATERNION",
)

# HIGHRES_IMU_UPDATED_FLAGS / HIL_SENSOR_UPDATED_FLAGS bits (common.xml)
_IMU_BITS = {
    "ax": 0, "ay": 1, "az": 2, "p": 3, "q": 4, "r": 5,
    "p_static": 9, "qbar": 10, "h": 11, "temperature": 12,
}

# WGS-84 radii for the flat-earth north/east -> latitude/longitude step
_WGS_A, _WGS_E2 = 6378137.0, 6.69437999014e-3


def frame_size(name: str) -> int:
    """Largest MAVLink 2 frame of a message, unsigned: 10 header + payload + 2 CRC.

    Parameters
    ----------
    name : str
        Message name, e.g. ``HIGHRES_IMU``.

    Returns
    -------
    int
        Frame size, bytes.
    """
    return 12 + message_class(name).unpacker.size


def message_class(name: str) -> type:
    """The pymavlink class of a message given its name.

    Parameters
    ----------
    name : str
        Message name, e.g. ``HIGHRES_IMU``.

    Returns
    -------
    type
        The pymavlink message class (dialect ardupilotmega).

    Raises
    ------
    ValueError
        For an unknown message.
    """
    cls = getattr(mavlink2, f"MAVLink_{name.lower()}_message", None)
    if cls is None:
        raise ValueError(f"unknown MAVLink message {name!r} (dialect ardupilotmega)")
    return cls


@dataclass(frozen=True)
class ServoMap:
    """Surface positions as servo PWM (us), both ways; canonical signs (flightid.channels).

    A surface at ``+max`` reads 2000 us, at ``-max`` 1000 us, neutral 1500 us
    (1 us = max/500 of resolution); throttle 0..1 maps to 1000..2000 us. Channels follow
    the ArduPlane order: 1 aileron (da), 2 elevator (de), 3 throttle, 4 rudder (dr).
    Positions beyond +-max are clipped to the PWM range and counted as saturated.
    """

    da_max: float = 30 * DEG
    de_max: float = 30 * DEG
    dr_max: float = 30 * DEG
    da_channel: int = 1
    de_channel: int = 2
    throttle_channel: int = 3
    dr_channel: int = 4

    def channels(self) -> dict[str, int]:
        """Canonical control name -> servo output number (1-based)."""
        return {
            "da": self.da_channel,
            "de": self.de_channel,
            "throttle": self.throttle_channel,
            "dr": self.dr_channel,
        }

    def limit(self, name: str) -> float:
        """Full deflection (rad) of a surface, or 1 for the throttle."""
        return 1.0 if name == "throttle" else getattr(self, f"{name}_max")

    def to_pwm(self, name: str, value: float) -> tuple[int, bool]:
        """PWM (us) for a surface (rad) or throttle (0..1), and whether it was clipped."""
        if not math.isfinite(value):
            return 0, False  # 0 = output not in use (SERVO_OUTPUT_RAW)
        if name == "throttle":
            raw = 1000.0 + 1000.0 * value
        else:
            raw = 1500.0 + 500.0 * value / self.limit(name)
        pwm = int(round(raw))
        clipped = min(max(pwm, 1000), 2000)
        return clipped, clipped != pwm

    def from_pwm(self, name: str, pwm: float) -> float:
        """Surface (rad) or throttle (0..1) from PWM (us); NaN for 0 (unused output)."""
        if pwm == 0:
            return NAN
        if name == "throttle":
            return (pwm - 1000.0) / 1000.0
        return (pwm - 1500.0) / 500.0 * self.limit(name)

    def resolution(self, name: str) -> float:
        """Value of one PWM microsecond (rad, or throttle fraction)."""
        return 1e-3 if name == "throttle" else self.limit(name) / 500.0


@dataclass(frozen=True)
class GeoOrigin:
    """Where north = east = 0 lies when a record has no latitude/longitude (rad, m MSL).

    Default: an arbitrary field near Melbourne, where the Monash Boomerang 60 flew.
    """

    latitude: float = -38.0 * DEG
    longitude: float = 145.2 * DEG


def euler_to_quaternion(phi: float, theta: float, psi: float) -> tuple[float, ...]:
    """Quaternion (w, x, y, z) of 3-2-1 Euler angles (Stevens & Lewis 2003, 1.8).

    Parameters
    ----------
    phi, theta, psi : float
        Roll, pitch and yaw angles, rad.

    Returns
    -------
    tuple of float
        Unit quaternion (w, x, y, z).
    """
    cr, sr = math.cos(phi / 2), math.sin(phi / 2)
    cp, sp = math.cos(theta / 2), math.sin(theta / 2)
    cy, sy = math.cos(psi / 2), math.sin(psi / 2)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def quaternion_to_euler(q: tuple[float, ...]) -> tuple[float, float, float]:
    """3-2-1 Euler angles of a quaternion (w, x, y, z).

    Parameters
    ----------
    q : tuple of float
        Unit quaternion (w, x, y, z).

    Returns
    -------
    tuple of float
        (phi, theta, psi), rad.
    """
    w, x, y, z = q
    phi = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    theta = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    psi = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return phi, theta, psi


def wrap_pi(angle: float) -> float:
    """Angle wrapped to [-pi, pi).

    Parameters
    ----------
    angle : float
        Angle, rad.

    Returns
    -------
    float
        The wrapped angle, rad.
    """
    return (angle + math.pi) % (2 * math.pi) - math.pi


class TelemetryState:
    """Builds, sample by sample, the values the messages need from canonical channels.

    Adds what a record may lack but an onboard recorder measures: static pressure and
    dynamic pressure (ISA at h, 0.5 rho V^2), latitude/longitude from north/east
    (flat earth about ``origin``), and NED ground velocity by backward differences.
    """

    def __init__(self, origin: GeoOrigin | None = None) -> None:
        self.origin = origin or GeoOrigin()
        self._prev: tuple[float, float, float, float] | None = None  # t, north, east, h

    def sample(self, t: float, channels: Mapping[str, float]) -> dict[str, float]:
        """Canonical values at time t (s) plus derived ``p_static``, ``temperature`` (degC),
        ``vn``, ``ve``, ``vd`` (m/s), ``ias`` (m/s), ``latitude``/``longitude`` (rad)."""
        s = {k: float(v) for k, v in channels.items()}
        g = s.get
        h = g("h", NAN)
        p_isa, t_isa, rho_isa = isa(h) if math.isfinite(h) else (NAN, NAN, NAN)
        s.setdefault("p_static", p_isa)
        s["temperature"] = t_isa - 273.15
        rho = g("rho", rho_isa)
        V = g("V", NAN)
        s.setdefault("qbar", 0.5 * rho * V * V)
        s["ias"] = V * math.sqrt(rho / RHO0)  # equivalent airspeed as the IAS
        north, east = g("north", NAN), g("east", NAN)
        if "latitude" not in s and math.isfinite(north) and math.isfinite(east):
            lat0 = self.origin.latitude
            den = math.sqrt(1 - _WGS_E2 * math.sin(lat0) ** 2)
            r_meridian = _WGS_A * (1 - _WGS_E2) / den**3
            r_normal = _WGS_A / den
            s["latitude"] = lat0 + north / r_meridian
            s["longitude"] = self.origin.longitude + east / (r_normal * math.cos(lat0))
        vn = ve = vd = NAN
        if self._prev is not None and t > self._prev[0]:
            dt = t - self._prev[0]
            vn = (north - self._prev[1]) / dt
            ve = (east - self._prev[2]) / dt
            vd = -(h - self._prev[3]) / dt
        s["vn"], s["ve"], s["vd"] = vn, ve, vd
        self._prev = (t, north, east, h)
        return s


@dataclass
class EncodeContext:
    """What every encoder needs besides the sample: mappings and the common time base."""

    servo_map: ServoMap
    epoch_unix_usec: int  # unix time (us) of sim time 0: the common (GPS) clock
    mav_type: int = mavlink2.MAV_TYPE_FIXED_WING
    saturated: int = 0  # servo samples clipped so far


def _f(x: float) -> float:
    return float(x) if x is not None else NAN


def _fields_updated(s: Mapping[str, float]) -> int:
    return sum(1 << bit for name, bit in _IMU_BITS.items() if math.isfinite(s.get(name, NAN)))


def _i(x: float, lo: int, hi: int, unknown: int) -> int:
    return int(min(max(round(x), lo), hi)) if math.isfinite(x) else unknown


def encode(
    name: str, s: Mapping[str, float], t_true: float, t_local: float, ctx: EncodeContext
):
    """The MAVLink message ``name`` for one sample.

    Parameters
    ----------
    name : str
        Message name, one of ``TELEMETRY``.
    s : Mapping of str to float
        The sample: canonical channels by name, SI.
    t_true : float
        Sim time, s.
    t_local : float
        Recorder clock, s.
    ctx : EncodeContext
        Servo mapping, common time base and vehicle type.

    Returns
    -------
    pymavlink message
        The message, ready to pack.

    Raises
    ------
    ValueError
        For a message the bridge cannot encode.
    """
    g = lambda k: s.get(k, NAN)  # noqa: E731
    usec = int(round(t_local * 1e6))
    if name == "HEARTBEAT":
        return mavlink2.MAVLink_heartbeat_message(
            ctx.mav_type, mavlink2.MAV_AUTOPILOT_GENERIC,
            mavlink2.MAV_MODE_FLAG_HIL_ENABLED, 0, mavlink2.MAV_STATE_ACTIVE, 3,
        )
    if name == "SYSTEM_TIME":
        return mavlink2.MAVLink_system_time_message(
            ctx.epoch_unix_usec + int(round(t_true * 1e6)), int(round(t_local * 1e3)) % 2**32
        )
    if name in ("HIGHRES_IMU", "HIL_SENSOR"):
        cls = (mavlink2.MAVLink_highres_imu_message if name == "HIGHRES_IMU"
               else mavlink2.MAVLink_hil_sensor_message)
        return cls(
            usec, g("ax"), g("ay"), g("az"), g("p"), g("q"), g("r"), NAN, NAN, NAN,
            g("p_static") / 100.0, g("qbar") / 100.0, g("h"), g("temperature"),
            _fields_updated(s), 0,
        )
    if name == "ATTITUDE":
        return mavlink2.MAVLink_attitude_message(
            int(round(t_local * 1e3)) % 2**32, g("phi"), g("theta"), wrap_pi(g("psi")),
            g("p"), g("q"), g("r"),
        )
    if name == "AOA_SSA":
        return mavlink2.MAVLink_aoa_ssa_message(usec, g("alpha") / DEG, g("beta") / DEG)
    if name == "VFR_HUD":
        heading = g("psi") / DEG % 360.0 if math.isfinite(g("psi")) else NAN
        return mavlink2.MAVLink_vfr_hud_message(
            g("V"), math.hypot(g("vn"), g("ve")), _i(heading, 0, 359, 0) % 360,
            _i(100 * g("throttle"), 0, 100, 0), g("h"), -g("vd"),
        )
    if name == "SERVO_OUTPUT_RAW":
        pwm = [0] * 8
        for ch, out in ctx.servo_map.channels().items():
            value, clipped = ctx.servo_map.to_pwm(ch, g(ch))
            ctx.saturated += clipped
            pwm[out - 1] = value
        return mavlink2.MAVLink_servo_output_raw_message(usec % 2**32, 0, *pwm)
    if name == "GPS_RAW_INT":
        lat, lon = g("latitude"), g("longitude")
        fix = 3 if math.isfinite(lat) and math.isfinite(lon) else 0
        vel = 100 * math.hypot(g("vn"), g("ve"))
        cog = 100 * (math.atan2(g("ve"), g("vn")) / DEG % 360.0)
        return mavlink2.MAVLink_gps_raw_int_message(
            usec, fix, _i(lat / DEG * 1e7, -(2**31), 2**31 - 1, 0),
            _i(lon / DEG * 1e7, -(2**31), 2**31 - 1, 0), _i(g("h") * 1e3, -(2**31), 2**31 - 1, 0),
            UINT16_MAX, UINT16_MAX, _i(vel, 0, UINT16_MAX - 1, UINT16_MAX),
            _i(cog, 0, 35999, UINT16_MAX), 10 if fix else 0,
        )
    if name == "HIL_STATE_QUATERNION":
        quat = euler_to_quaternion(g("phi"), g("theta"), g("psi"))
        big = 2**31 - 1
        return mavlink2.MAVLink_hil_state_quaternion_message(
            usec, list(quat), g("p"), g("q"), g("r"),
            _i(g("latitude") / DEG * 1e7, -big, big, 0),
            _i(g("longitude") / DEG * 1e7, -big, big, 0), _i(g("h") * 1e3, -big, big, 0),
            _i(100 * g("vn"), -32767, 32767, 0), _i(100 * g("ve"), -32767, 32767, 0),
            _i(100 * g("vd"), -32767, 32767, 0),
            _i(100 * g("ias"), 0, UINT16_MAX, 0), _i(100 * g("V"), 0, UINT16_MAX, 0),
            _i(1000 * g("ax") / G0, -32767, 32767, 0), _i(1000 * g("ay") / G0, -32767, 32767, 0),
            _i(1000 * g("az") / G0, -32767, 32767, 0),
        )
    raise ValueError(f"the bridge cannot encode {name!r}; it sends {', '.join(TELEMETRY)}")
