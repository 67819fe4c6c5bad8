"""The recorder bridge writes a flight as an ArduPilot DataFlash log (``.bin``), the way
an ArduPlane vehicle logs it: FMT-described messages with ArduPilot's names, formats,
units and multipliers (``flightid.importers.dataflash_formats``), each at its own rate
on the autopilot's microsecond clock (TimeUS since boot), servo outputs as PWM.

Rates (Hz), after ArduPlane's scheduler with its default log bit mask: IMU 50, ATT 25,
RCOU 25, AOA 10, ARSP 10, CTUN 10, BARO 10, GPS 5 (a 5 Hz receiver). Each message samples
the record's channels at its own times (linear interpolation; at a rate that divides the
record's, the record's own samples).

What the logging does to the values: float32 fields (IMU, ARSP, AOA) keep 24 bits of
mantissa; ATT angles are whole centidegrees; RCOU outputs whole microseconds of PWM
(a surface's throw / 500 per microsecond); GPS latitude and longitude are 1e-7 deg and
its altitude whole centimetres. ARSP logs the equivalent airspeed, V sqrt(rho / rho0)
with the ISA density at the record's altitude, and qbar as the differential pressure;
BARO logs the ISA static pressure at h (or the record's p_static) and the altitude above
the first sample.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pymavlink.DFReader import FORMAT_TO_STRUCT

from flightid.atmosphere import P0, RHO0, T0, isa_density
from flightid.files import atomic_path
from flightid.importers.dataflash_formats import (
    BY_NAME,
    FMT_ID,
    FORMATS,
    MULTS,
    RCOU_OUTPUTS,
    SERVO_DEFLECTION_SIGN,
    SERVO_FUNCTIONS,
    UNITS,
    LogFormat,
)
from flightid.importers.servos import ServoMapping
from flightid.record import FlightRecord
from flightid.units import DEG

HEAD = bytes([0xA3, 0x95])
RATES: dict[str, float] = {"IMU": 50.0, "ATT": 25.0, "RCOU": 25.0, "AOA": 10.0,
                           "ARSP": 10.0, "CTUN": 10.0, "BARO": 10.0, "GPS": 5.0}
BOOT_S = 41.25  # the flight starts this long after the autopilot booted (s)
GPS_EPOCH_UNIX = 315_964_800  # 1980-01-06 00:00:00 UTC
GPS_LEAP_S = 18  # GPS - UTC since 2017
START_UNIX = 1_780_315_200  # the log's first sample: 2026-06-01 12:00:00 UTC
WEEK_S = 604_800


@dataclass(frozen=True)
class SysIdRun:
    """One chirp of ArduPilot's system-identification mode as its SIDS message states it:
    the axis (SID_AXIS, e.g. 11 pitch mixer), the start (s, record time), the chirp's
    duration TR (s), its start and stop frequencies (Hz), magnitude, fade-in and fade-out
    times (s). SIDD is logged at the IMU's rate from the start to TR + TFout after it."""

    axis: int
    start: float
    record_s: float
    f_start_hz: float
    f_stop_hz: float
    magnitude: float = 1.0
    fade_in_s: float = 0.0
    fade_out_s: float = 0.0


def _struct(fmt: str) -> struct.Struct:
    return struct.Struct("<" + "".join(FORMAT_TO_STRUCT[c][0] for c in fmt))


def _text(value: str, size: int) -> bytes:
    return value.encode("ascii")[:size].ljust(size, b"\0")


def _fmt_message(f: LogFormat) -> bytes:
    length = 3 + _struct(f.format).size
    return HEAD + bytes([FMT_ID]) + struct.pack("<BB4s16s64s", f.type_id, length,
                                                _text(f.name, 4), _text(f.format, 16),
                                                _text(f.columns, 64))


def _pack(f: LogFormat, *values) -> bytes:
    return HEAD + bytes([f.type_id]) + _struct(f.format).pack(*values)


def _header(servos: ServoMapping) -> list[bytes]:
    """FMT of FMT and of every message, then UNIT, MULT, FMTU, the servo parameters."""
    fmt_of_fmt = HEAD + bytes([FMT_ID]) + struct.pack(
        "<BB4s16s64s", FMT_ID, 89, b"FMT\0", _text("BBnNZ", 16),
        _text("Type,Length,Name,Format,Columns", 64))
    out = [fmt_of_fmt, *(_fmt_message(f) for f in FORMATS)]
    out += [_pack(BY_NAME["UNIT"], 0, ord(k), _text(v, 64)) for k, v in UNITS.items()]
    out += [_pack(BY_NAME["MULT"], 0, ord(k), v) for k, v in MULTS.items()]
    out += [_pack(BY_NAME["FMTU"], 0, f.type_id, _text(f.units, 16), _text(f.mults, 16))
            for f in FORMATS]
    out.append(_pack(BY_NAME["MSG"], 0, _text("flightid bridge: ArduPlane-style DataFlash "
                                              "log of a JSBSim flight", 64)))
    params: list[tuple[str, float]] = []
    for name, servo in servos.surfaces.items():
        params += [(f"SERVO{servo.channel}_FUNCTION", SERVO_FUNCTIONS[name]),
                   (f"SERVO{servo.channel}_TRIM", servo.trim),
                   (f"SERVO{servo.channel}_REVERSED",
                    1.0 if servo.throw * SERVO_DEFLECTION_SIGN[name] < 0 else 0.0)]
    if servos.throttle is not None:
        c = servos.throttle.channel
        params += [(f"SERVO{c}_FUNCTION", SERVO_FUNCTIONS["throttle"]),
                   (f"SERVO{c}_MIN", servos.throttle.low), (f"SERVO{c}_MAX",
                                                            servos.throttle.high)]
    out += [_pack(BY_NAME["PARM"], 0, _text(n, 16), float(v), float(v)) for n, v in params]
    return out


def message_times(record: FlightRecord, rate: float) -> np.ndarray:
    """Times of a message sent at ``rate`` over the record, from its start.

    Parameters
    ----------
    record : FlightRecord
        The flight; its first and last time bound the messages.
    rate : float
        Message rate, Hz.

    Returns
    -------
    numpy.ndarray
        Send times, s.
    """
    t0, t1 = float(record.time[0]), float(record.time[-1])
    return t0 + np.arange(int(math.floor((t1 - t0) * rate + 1e-6)) + 1) / rate


def sampled(record: FlightRecord, t: np.ndarray, name: str, default: float = math.nan
            ) -> np.ndarray:
    """Channel ``name`` at times ``t`` (linear interpolation), or ``default`` when absent.

    Parameters
    ----------
    record : FlightRecord
        The flight.
    t : numpy.ndarray
        Times, s.
    name : str
        Channel name.
    default : float, optional
        Value when the record lacks the channel. Default NaN.

    Returns
    -------
    numpy.ndarray
        Channel values in its SI unit; same shape as ``t``.
    """
    if name not in record:
        return np.full(t.size, default)
    return np.interp(t, record.time, record[name])


def _cd(rad: np.ndarray) -> np.ndarray:
    """Whole centidegrees (int16 'c' fields)."""
    return np.round(np.asarray(rad) / DEG * 100.0).astype(int)


def write_dataflash(record: FlightRecord, path: str | Path, *,
                    servos: ServoMapping | None = None,
                    rates: dict[str, float] | None = None,
                    sysid: Sequence[SysIdRun] = ()) -> Path:
    """Write ``record`` (SI, canonical channels) as an ArduPlane-style DataFlash log.

    Parameters
    ----------
    record : the flight; needs p, q, r, ax, ay, az, phi, theta, psi, V and the controls of
        ``servos``; alpha, beta, qbar, h, latitude, longitude are logged when present.
        The servo outputs (RCOU and CTUN) carry its ``de da dr throttle``: to log
        commands that differ from the surface positions (ahead of a servo lag), pass
        ``record.with_channels(de=commanded, ...)``; no other message reads them.
    path : the ``.bin`` file (written atomically).
    servos : surfaces and throttle to servo outputs (default ArduPlane's order).
    rates : message -> rate (Hz) over :data:`RATES`; a message at rate 0 is left out.
    sysid : chirps of ArduPilot's system-identification mode to log as SIDS and SIDD
        (the flight itself is not changed: the record's inputs are what was flown).

    Returns
    -------
    The path written.
    """
    servos = servos or ServoMapping()
    rates = {**RATES, **(rates or {})}
    need = ["p", "q", "r", "ax", "ay", "az", "phi", "theta", "psi", "V",
            *servos.outputs()]
    missing = [c for c in need if c not in record]
    if missing:
        raise ValueError(f"record lacks {', '.join(missing)}: a DataFlash log of it needs "
                         f"{', '.join(need)}")
    rows: list[tuple[int, int, bytes]] = []  # (TimeUS, order, message)

    def add(name: str, build) -> None:
        rate = rates.get(name, 0.0)
        if not rate > 0:
            return
        t = message_times(record, rate)
        us = np.round((t - record.time[0] + BOOT_S) * 1e6).astype(np.int64)
        order = list(RATES).index(name)
        for k, message in enumerate(build(t, us)):
            rows.append((int(us[k]), order, message))

    h = sampled(record, record.time, "h", 0.0)
    h0 = float(h[0])

    def imu(t, us):
        v = [sampled(record, t, c) for c in ("p", "q", "r", "ax", "ay", "az")]
        f = BY_NAME["IMU"]
        return [_pack(f, us[k], 0, *(x[k] for x in v), 0, 0, 25.0, 1, 1,
                      int(rates["IMU"]), int(rates["IMU"])) for k in range(t.size)]

    def att(t, us):
        roll, pitch = _cd(sampled(record, t, "phi")), _cd(sampled(record, t, "theta"))
        yaw = np.round((sampled(record, t, "psi") / DEG % 360.0) * 100.0).astype(int) % 36000
        f = BY_NAME["ATT"]
        return [_pack(f, us[k], roll[k], roll[k], pitch[k], pitch[k], yaw[k], yaw[k], 0, 0, 3)
                for k in range(t.size)]

    def aoa(t, us):
        a, b = sampled(record, t, "alpha") / DEG, sampled(record, t, "beta") / DEG
        return [_pack(BY_NAME["AOA"], us[k], a[k], b[k]) for k in range(t.size)]

    def eas(t):
        rho = isa_density(sampled(record, t, "h", 0.0))
        return sampled(record, t, "V") * np.sqrt(rho / RHO0)

    def temperature_cdeg(t):
        return np.round((T0 - 0.0065 * sampled(record, t, "h", 0.0) - 273.15) * 100).astype(int)

    def arsp(t, us):
        speed, temp = eas(t), temperature_cdeg(t)
        qbar = sampled(record, t, "qbar", math.nan)
        qbar = np.where(np.isfinite(qbar), qbar, 0.5 * RHO0 * speed**2)
        return [_pack(BY_NAME["ARSP"], us[k], 0, speed[k], qbar[k], temp[k], qbar[k], 0.0)
                for k in range(t.size)]

    def ctun(t, us):
        roll, pitch = _cd(sampled(record, t, "phi")), _cd(sampled(record, t, "theta"))
        throttle = np.round(100 * sampled(record, t, "throttle", 0.0)).astype(int)
        rudder = np.zeros(t.size, dtype=int)
        if "dr" in servos.surfaces:
            # ArduPilot's scaled rudder (+-4500) is a yaw demand, nose right positive
            rudder = np.round(-4500 * sampled(record, t, "dr", 0.0) /
                              abs(servos.surfaces["dr"].throw)).astype(int)
        speed = eas(t)
        return [_pack(BY_NAME["CTUN"], us[k], roll[k], roll[k], pitch[k], pitch[k],
                      throttle[k], rudder[k], throttle[k], speed[k]) for k in range(t.size)]

    def rcou(t, us):
        pwm = np.zeros((t.size, RCOU_OUTPUTS), dtype=int)
        for name, servo in servos.surfaces.items():
            pwm[:, servo.channel - 1] = servo.pwm(sampled(record, t, name))
        if servos.throttle is not None:
            pwm[:, servos.throttle.channel - 1] = servos.throttle.pwm(
                sampled(record, t, "throttle"))
        pwm = np.clip(pwm, 0, 65535)
        return [_pack(BY_NAME["RCOU"], us[k], *map(int, pwm[k])) for k in range(t.size)]

    def baro(t, us):
        alt = sampled(record, t, "h", 0.0)
        press = sampled(record, t, "p_static")
        isa_p = P0 * ((T0 - 0.0065 * alt) / T0) ** 5.2558774324716
        press = np.where(np.isfinite(press), press, isa_p)
        climb = np.gradient(alt, t) if t.size > 1 else np.zeros(t.size)
        temp = temperature_cdeg(t)
        sms = np.round(us * 1e-3).astype(np.int64) % 2**32
        return [_pack(BY_NAME["BARO"], us[k], 0, alt[k] - h0, press[k], temp[k], climb[k],
                      int(sms[k]), 0.0, 15.0, 1) for k in range(t.size)]

    def gps(t, us):
        lat = np.round(sampled(record, t, "latitude", 0.0) / DEG * 1e7).astype(np.int64)
        lng = np.round(sampled(record, t, "longitude", 0.0) / DEG * 1e7).astype(np.int64)
        alt = np.round(sampled(record, t, "h", 0.0) * 100).astype(np.int64)
        speed = sampled(record, t, "V")
        course = (sampled(record, t, "psi", 0.0) / DEG) % 360.0
        gps_s = START_UNIX - GPS_EPOCH_UNIX + GPS_LEAP_S + (t - record.time[0])
        week = (gps_s // WEEK_S).astype(int)
        ms = np.round((gps_s - week * WEEK_S) * 1000).astype(np.int64)
        return [_pack(BY_NAME["GPS"], us[k], 0, 3, int(ms[k]), int(week[k]), 12, 100,
                      int(lat[k]), int(lng[k]), int(alt[k]), speed[k], course[k], 0.0, 0.0,
                      1) for k in range(t.size)]

    builders = {"IMU": imu, "ATT": att, "RCOU": rcou, "AOA": aoa, "ARSP": arsp,
                "CTUN": ctun, "BARO": baro, "GPS": gps}
    for name, build in builders.items():
        if name == "AOA" and ("alpha" not in record or "beta" not in record):
            continue
        if name == "GPS" and "latitude" not in record:
            continue
        add(name, build)
    for run in sysid:
        rows.extend(_sysid_rows(record, run, rates["IMU"]))
    rows.sort(key=lambda r: (r[0], r[1]))
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        for message in _header(servos):
            fh.write(message)
        for _, _, message in rows:
            fh.write(message)
    return path


def _sysid_rows(record: FlightRecord, run: SysIdRun, rate: float) -> list[tuple[int, int,
                                                                                  bytes]]:
    """SIDS at the run's start and SIDD at ``rate`` (Hz) until TR + TFout after it: the
    chirp's time, the frequency of an exponential sweep from FSt to FSp over TR, body rates
    (deg/s) and specific force (m/s^2) of the record."""
    us0 = round((run.start - record.time[0] + BOOT_S) * 1e6)
    order = len(RATES)
    rows = [(us0, order, _pack(BY_NAME["SIDS"], us0, run.axis, run.magnitude, run.f_start_hz,
                               run.f_stop_hz, run.fade_in_s, 0.0, run.record_s,
                               run.fade_out_s))]
    n = int(math.floor((run.record_s + run.fade_out_s) * rate + 1e-6)) + 1
    tau = np.arange(n) / rate
    t = run.start + tau
    ratio = run.f_stop_hz / run.f_start_hz if run.f_start_hz > 0 else 1.0
    freq = run.f_start_hz * ratio ** np.clip(tau / max(run.record_s, 1e-9), 0.0, 1.0)
    rates_deg = [sampled(record, t, c) / DEG for c in ("p", "q", "r")]
    force = [sampled(record, t, c) for c in ("ax", "ay", "az")]
    for k in range(n):
        us = us0 + round(tau[k] * 1e6)
        rows.append((us, order + 1, _pack(BY_NAME["SIDD"], us, tau[k], 0.0, freq[k],
                                          *(x[k] for x in rates_deg), *(x[k] for x in force))))
    return rows
