"""ArduPilot DataFlash logs (``.bin``) into a FlightRecord, read with pymavlink's
``DFReader`` (the loader of MAVExplorer and mavlogdump).

Messages used (ArduPlane names, ``dataflash_formats``):

* IMU (instance 0): body rates p, q, r (rad/s) and specific force ax, ay, az (m/s^2);
* ATT: phi, theta (centidegrees) and psi (0-360 deg, unwrapped);
* ARSP (instance 0) or, without it, CTUN: airspeed. ArduPilot logs the equivalent
  airspeed; it becomes true airspeed V with the ISA density at the barometric pressure
  altitude (EAS * sqrt(rho0 / rho), Anderson, Introduction to Flight, sec. 4.12); ARSP's
  differential pressure is qbar (Pa);
* RCOU: servo outputs (PWM, us) mapped to de, da, dr, throttle through a
  :class:`~flightid.importers.servos.ServoMapping`: these are COMMANDS, not surface
  positions, and the record says so (``meta.extra['surfaces'] = 'command'``). Without a
  mapping, the log's own parameters give the outputs (SERVOn_FUNCTION), the trims
  (SERVOn_TRIM), the reversals (SERVOn_REVERSED) and the throttle's range (SERVOn_MIN,
  SERVOn_MAX); the throws, which no parameter holds, are then 30 deg, and a note says so.
  An aileron, elevator or rudder output above trim, not reversed, is ArduPilot's demand
  for a positive moment: a negative deflection (``dataflash_formats.SERVO_DEFLECTION_SIGN``);
* AOA (alpha, beta in deg), BARO (static pressure, pressure altitude h), GPS (latitude,
  longitude) when the log has them;
* SIDS and SIDD (ArduPilot's system-identification mode): each chirp becomes a maneuver
  window in ``meta.extra['maneuvers']`` (the key the methods' windows read), on the
  control its axis (SID_AXIS) excites, from its SIDS message to its last SIDD message
  (without SIDD: to SIDS time + TR + TFout).

Every message carries TimeUS on the autopilot's one clock; each channel is interpolated
linearly from its own message times onto one uniform grid at the IMU's rate (or a given
rate) over the span the needed messages share. Other instances (a second IMU), messages
not listed and the PARM/MSG texts are not kept; the counts are in
``meta.extra['dataflash']``. A log cut in the middle of a message keeps every whole
message before the cut and says how many bytes were dropped.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from pymavlink import DFReader

from flightid.atmosphere import RHO0, isa_density, isa_pressure_altitude
from flightid.console import captured_output
from flightid.flight_record import FlightRecord, RecordMeta, check_samples
from flightid.importers.dataflash_formats import (
    SERVO_DEFLECTION_SIGN,
    SERVO_FUNCTIONS,
    SYSID_AXES,
)
from flightid.importers.servos import Servo, ServoMapping, Throttle
from flightid.units import DEG

HEAD = bytes([0xA3, 0x95])  # every DataFlash message starts with these
REQUIRED = ("IMU", "ATT", "RCOU")
AIRSPEED = ("ARSP", "CTUN")  # one of them
OPTIONAL = ("AOA", "BARO", "GPS")
# message -> fields read (TimeUS always)
FIELDS: dict[str, tuple[str, ...]] = {
    "IMU": ("GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ"),
    "ATT": ("Roll", "Pitch", "Yaw"),
    "ARSP": ("Airspeed", "DiffPress"),
    "CTUN": ("Aspd",),
    "RCOU": tuple(f"C{i}" for i in range(1, 15)),
    "AOA": ("AOA", "SSA"),
    "BARO": ("Press",),
    "GPS": ("Lat", "Lng", "Alt"),
    "SIDS": ("Ax", "Mag", "FSt", "FSp", "TR", "TFout"),
    "SIDD": ("Time",),
}
DEFAULT_THROW = 30 * DEG  # rad per 500 us when the throws are not given
CONDITION_CHANNELS = ("V", "h", "alpha", "beta", "qbar", "mass")


def _collect(path: Path) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, int], int,
                                  list[str], dict[str, float]]:
    """Per message: TimeUS (s) and fields of instance 0; counts of every message type;
    bytes after the last whole message; what DFReader complained about; the parameters
    (PARM, last value of each)."""
    rows: dict[str, list[list[float]]] = {k: [] for k in FIELDS}
    counts: dict[str, int] = {}
    params: dict[str, float] = {}
    other_instances: dict[str, int] = {}
    with open(path, "rb") as fh:
        head = fh.read(3)
    if head[:2] != HEAD:
        raise ValueError(f"{path}: not a DataFlash log: it does not start with a DataFlash "
                         f"message (bytes A3 95; it starts with {head.hex(' ') or 'nothing'})")
    with captured_output() as said:  # DFReader's indexer prints to the process's stderr
        try:
            log = DFReader.DFReader_binary(str(path), zero_time_base=True)
        except Exception as exc:  # DFReader raises assorted types on a foreign file
            raise ValueError(f"{path}: not a readable DataFlash log ({type(exc).__name__}: "
                             f"{exc})") from None
        end = 0
        while True:
            msg = log.recv_msg()
            if msg is None:
                break
            end = log.offset
            kind = msg.get_type()
            counts[kind] = counts.get(kind, 0) + 1
            if kind == "PARM":
                params[str(msg.Name)] = float(msg.Value)
            if kind not in FIELDS or "TimeUS" not in msg.get_fieldnames():
                continue
            if "I" in msg.get_fieldnames() and getattr(msg, "I", 0) != 0:
                other_instances[kind] = other_instances.get(kind, 0) + 1
                continue
            rows[kind].append([msg.TimeUS * 1e-6, *(float(getattr(msg, f)) for f in
                                                    FIELDS[kind])])
        size = log.data_len
    skipped = sum(line.startswith("bad header") for line in said)
    notes = [f"{skipped} unreadable byte(s) skipped (damage inside the log); the whole "
             "messages around them kept"] if skipped else []
    others = [line for line in said if not line.startswith("bad header")]
    notes += [f"pymavlink: {line}" for line in others[:3]]
    if len(others) > 3:
        notes.append(f"pymavlink: {len(others) - 3} more line(s)")
    notes += [f"{n} {k} message(s) of other instances not kept" for k, n in
              other_instances.items()]
    series = {}
    for kind, values in rows.items():
        if values:
            arr = np.array(values)
            series[kind] = {"t": arr[:, 0], **{f: arr[:, i + 1] for i, f in
                                               enumerate(FIELDS[kind])}}
    return series, counts, size - end, notes, params


def servos_from_params(params: dict[str, float]) -> ServoMapping | None:
    """The servo mapping the log's ArduPilot parameters give (module docstring), with
    :data:`DEFAULT_THROW`; None when no SERVOn_FUNCTION names a control.

    Parameters
    ----------
    params : the log's PARM values, name -> value.

    Returns
    -------
    ServoMapping, or None. A surface's throw has the sign of flightid's deflection for an
    output above trim (``dataflash_formats.SERVO_DEFLECTION_SIGN``: an aileron, elevator or
    rudder output above trim asks for a positive moment, a negative deflection), turned
    over on a reversed output.
    """
    functions = {int(v): k for k, v in SERVO_FUNCTIONS.items()}
    surfaces: dict[str, Servo] = {}
    throttle = None
    for n in range(1, 17):
        name = functions.get(int(params.get(f"SERVO{n}_FUNCTION", 0)))
        if name is None or n > 14:
            continue
        sign = -1.0 if params.get(f"SERVO{n}_REVERSED", 0) else 1.0
        if name == "throttle":
            low, high = params.get(f"SERVO{n}_MIN", 1000.0), params.get(f"SERVO{n}_MAX", 2000.0)
            throttle = Throttle(n, high, low) if sign < 0 else Throttle(n, low, high)
        elif name not in surfaces:
            trim = params.get(f"SERVO{n}_TRIM", 1500.0)
            throw = sign * SERVO_DEFLECTION_SIGN[name] * DEFAULT_THROW
            low, high = params.get(f"SERVO{n}_MIN"), params.get(f"SERVO{n}_MAX")
            # ArduPilot scales a demand onto trim..max above trim and min..trim below it
            # (SRV_Channel::pwm_from_angle): the same demand, the same deflection
            below = throw * (high - trim) / (trim - low) if low is not None and \
                high is not None and low < trim < high else None
            surfaces[name] = Servo(n, trim, throw, below)
    if not surfaces and throttle is None:
        return None
    return ServoMapping(surfaces, throttle)


def _increasing(kind: str, s: dict[str, np.ndarray], notes: list[str]) -> dict[str, np.ndarray]:
    """The messages of one type whose time increases (a repeated or earlier TimeUS is
    dropped and counted)."""
    t = s["t"]
    keep = np.concatenate([[True], np.diff(t) > 0])
    keep &= t >= np.maximum.accumulate(t)
    if not keep.all():
        notes.append(f"{int((~keep).sum())} {kind} message(s) with a repeated or earlier "
                     "TimeUS dropped")
    return {k: v[keep] for k, v in s.items()}


def read_dataflash(path: str | Path, servos: ServoMapping | None = None,
                   rate: float | None = None) -> FlightRecord:
    """Read an ArduPilot DataFlash log into a FlightRecord in SI units (module docstring).

    Parameters
    ----------
    path : the ``.bin`` log.
    servos : servo outputs to surfaces (default: the log's SERVOn_ parameters with 30 deg
        throws, else ArduPlane's order, 1500 us trims, 30 deg throws).
    rate : output rate (Hz); default the IMU's.

    Returns
    -------
    FlightRecord with time in s since the autopilot booted, ``meta.extra['surfaces'] =
    'command'`` and ``meta.extra['dataflash']`` (message counts, rate, servo mapping, what
    was dropped).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    series, counts, cut_bytes, notes, params = _collect(path)
    if servos is None:
        servos = servos_from_params(params)
        if servos is None:
            servos = ServoMapping()
            notes.append("no servo mapping given and no SERVOn_FUNCTION parameter in the "
                         "log: ArduPlane's output order with 30 deg throws assumed")
        else:
            notes.append("servo outputs, trims and throttle range from the log's SERVOn_ "
                         "parameters; throws are in no parameter: 30 deg assumed (give a "
                         "servo mapping for the real ones)")
    missing = [k for k in REQUIRED if k not in series]
    if not any(k in series for k in AIRSPEED):
        missing.append(" or ".join(AIRSPEED))
    if missing:
        present = ", ".join(sorted(counts)) or "none"
        raise ValueError(f"{path}: the log lacks the message(s) {', '.join(missing)} that a "
                         f"flight record needs (IMU, ATT, RCOU, and ARSP or CTUN); it has: "
                         f"{present}")
    series = {k: _increasing(k, s, notes) for k, s in series.items()}
    if cut_bytes:
        notes.append(f"the log ends in a cut message: {cut_bytes} byte(s) after the last "
                     "whole message dropped")
    imu = series["IMU"]
    if imu["t"].size < 2:
        raise ValueError(f"{path}: fewer than two IMU messages")
    step = 1.0 / rate if rate else float(np.median(np.diff(imu["t"])))
    used = [k for k in (*REQUIRED, "ARSP" if "ARSP" in series else "CTUN") if k in series]
    lo = max(series[k]["t"][0] for k in used)
    hi = min(series[k]["t"][-1] for k in used)
    n = int(np.floor((hi - lo) / step + 1e-6)) + 1
    if n < 2:
        raise ValueError(f"{path}: the messages {', '.join(used)} share less than two "
                         f"samples of time ({lo:.3f} to {hi:.3f} s)")
    grid = lo + step * np.arange(n)

    def at(kind: str, name: str) -> np.ndarray:
        return np.interp(grid, series[kind]["t"], series[kind][name])

    ch: dict[str, np.ndarray] = {
        "p": at("IMU", "GyrX"), "q": at("IMU", "GyrY"), "r": at("IMU", "GyrZ"),
        "ax": at("IMU", "AccX"), "ay": at("IMU", "AccY"), "az": at("IMU", "AccZ"),
        "phi": at("ATT", "Roll") * DEG, "theta": at("ATT", "Pitch") * DEG,
    }
    att = series["ATT"]
    yaw = np.unwrap(att["Yaw"] * DEG)  # ArduPilot's 0-360 deg, started in (-pi, pi]
    ch["psi"] = np.interp(grid, att["t"], yaw - 2 * np.pi * np.round(yaw[0] / (2 * np.pi)))
    if "BARO" in series:
        ch["p_static"] = at("BARO", "Press")
        ch["h"] = isa_pressure_altitude(ch["p_static"])
    elif "GPS" in series:
        ch["h"] = at("GPS", "Alt")
    if "ARSP" in series:
        eas = at("ARSP", "Airspeed")
        ch["qbar"] = at("ARSP", "DiffPress")
    else:
        eas = at("CTUN", "Aspd")
        notes.append("no ARSP: airspeed from CTUN (no dynamic pressure)")
    if "h" in ch:
        ch["V"] = eas * np.sqrt(RHO0 / isa_density(ch["h"]))
    else:
        ch["V"] = eas
        notes.append("no BARO or GPS: V is ArduPilot's equivalent airspeed (no altitude "
                     "for the density)")
    if "AOA" in series:
        ch["alpha"], ch["beta"] = at("AOA", "AOA") * DEG, at("AOA", "SSA") * DEG
    if "GPS" in series:
        ch["latitude"], ch["longitude"] = at("GPS", "Lat") * DEG, at("GPS", "Lng") * DEG
    ch.update(_commands(path, series["RCOU"], grid, servos))
    check_samples(str(path), grid, ch)
    condition: dict[str, Any] = {k: float(np.mean(ch[k])) for k in CONDITION_CHANNELS
                                 if k in ch}
    condition["note"] = "means over the record (SI units), the reference of perturbation models"
    extra: dict[str, Any] = {
        "surfaces": "command",
        "dataflash": {
            "file": path.name, "counts": counts, "rate_hz": 1.0 / step,
            "span_s": [float(lo), float(hi)], "servos": servos.as_dict(),
            "dropped_bytes": int(cut_bytes), "notes": notes,
            "time": "s since the autopilot booted (TimeUS); every channel interpolated "
                    "linearly from its own message times onto this grid",
        },
    }
    if "SIDS" in series:
        extra["maneuvers"] = _chirps(series["SIDS"], series.get("SIDD"), grid, notes)
    meta = RecordMeta(condition=condition, sample_rate=1.0 / step, extra=extra,
                      provenance=f"ArduPilot DataFlash log {path.name} read by "
                                 "flightid.importers.dataflash (pymavlink DFReader)")
    return FlightRecord(grid, ch, meta)


def _commands(path: Path, rcou: dict[str, np.ndarray], grid: np.ndarray,
              servos: ServoMapping) -> dict[str, np.ndarray]:
    out = {}
    for name, output in servos.outputs().items():
        pwm = rcou[f"C{output}"]
        if not np.any(pwm):
            raise ValueError(f"{path}: servo output {output} (mapped to {name}) is 0 in every "
                             "RCOU message: the output is not in use; fix the servo mapping")
        if name == "throttle":
            values = servos.throttle.value(pwm)
        else:
            values = servos.surfaces[name].deflection(pwm)
        out[name] = np.interp(grid, rcou["t"], values)
    return out


def _chirps(sids: dict[str, np.ndarray], sidd: dict[str, np.ndarray] | None,
            grid: np.ndarray, notes: list[str]) -> list[dict[str, Any]]:
    """Maneuver windows [{"kind", "surfaces", "start", "end", ...}] (s) of the chirps of
    ArduPilot's system-identification mode, within the record's span."""
    out = []
    starts = sids["t"]
    for k, start in enumerate(starts):
        axis = int(sids["Ax"][k])
        surface = SYSID_AXES.get(axis)
        if surface is None:
            notes.append(f"SIDS at {start:.3f} s excites axis {axis}, not a control "
                         "surface or the throttle: no maneuver window")
            continue
        end = start + float(sids["TR"][k]) + float(sids["TFout"][k])
        if sidd is not None:
            following = starts[k + 1] if k + 1 < starts.size else np.inf
            mine = sidd["t"][(sidd["t"] >= start) & (sidd["t"] < following)]
            if mine.size:
                end = float(mine[-1])
        if end < grid[0] or start > grid[-1]:
            notes.append(f"chirp on {surface} at {start:.3f} s lies outside the record")
            continue
        out.append({"kind": "chirp", "surfaces": [surface],
                    "start": float(max(start, grid[0])), "end": float(min(end, grid[-1])),
                    "source": "ArduPilot SIDS/SIDD", "axis": axis,
                    "f_start_hz": float(sids["FSt"][k]), "f_stop_hz": float(sids["FSp"][k]),
                    "magnitude": float(sids["Mag"][k])})
    return out
