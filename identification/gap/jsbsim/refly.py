"""The corrected aircraft and the aircraft as is flown again in JSBSim, window by window:
the gap of the full nonlinear model, not only of its linearisation.

Each maneuver window of the diagnosed axis (``segments``) is flown open loop (a lateral
window from the record's own state at its start: sideslip, bank, roll and yaw rate; a
longitudinal one from the record's trim, through what precedes it) with the record's
measured surfaces, and with a constant offset on each of the axis's surfaces re-estimated
on that window while the aircraft is held as it is: the bias and initial conditions of a
prediction case, refitted with the model fixed (Morelli & Klein 2016, model validation by
prediction; the linear diagnosis refits the same nuisance terms on every window). The
gap per channel is the residual energy over the measured energy, means removed.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.effect_fit import CACHE
from flightid.identification.gap.jsbsim.write import gap_fractions, write_aircraft
from flightid.identification.gap.model.linearise import AXIS_OUTPUTS, start_condition
from flightid.identification.gap.segments import segments
from flightid.record import FlightRecord
from flightid.sim.augment import augment_cached
from flightid.sim.flight.simulation import DepartureError, fly
from flightid.sim.jsbsim.model import Model, load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.units import FT

OFFSET_LIMIT = math.radians(5.0)  # a surface offset beyond +-5 deg is no trim offset
OFFSET_SCALE = math.radians(0.5)  # the offsets' typical size (rad), for the solver
MAX_FLIGHTS = 30  # flights per window for the offsets' fit
DEPARTED = 10.0  # residual (in channel standard deviations) of each sample after a departure


@dataclass
class WindowFlight:
    """One window flown: the gap per channel, the refitted surface offsets (rad), the largest
    bank-angle error (deg; lateral windows with a phi channel) and the departure, if any."""

    gap: dict[str, float]
    offsets: dict[str, float]
    bank_error_deg: float | None
    departed: str | None


def start_state(tr: Trim, record: FlightRecord, window: FlightRecord) -> Trim:
    """``tr`` moved to the lateral state of ``window``'s first sample: sideslip by its change
    since ``record``'s first sample (taken as the trim: a vane's bias cancels), bank angle
    and roll and yaw rate as measured. Airspeed, alpha and attitude stay at the trim: a
    JSBSim engine started at another airspeed goes through a transient of its own (a
    propeller 5 % slow for 2 s) that the aircraft in flight did not have.

    Parameters
    ----------
    tr : Trim
        The aircraft's trim where the record starts.
    record : FlightRecord
        The record.
    window : FlightRecord
        One of its windows.

    Returns
    -------
    Trim
        ``tr`` with its JSBSim initial conditions moved (sideslip, bank, roll and yaw
        rate).
    """
    js = dict(tr.jsbsim)
    V, a = tr.speed_m_s, tr.alpha
    b = tr.beta + (float(window["beta"][0]) - float(record["beta"][0])
                   if "beta" in record else 0.0)
    js["ic/u-fps"] = V * math.cos(a) * math.cos(b) / FT
    js["ic/v-fps"] = V * math.sin(b) / FT
    js["ic/w-fps"] = V * math.sin(a) * math.cos(b) / FT
    for name, key in (("phi", "ic/phi-rad"), ("p", "ic/p-rad_sec"), ("r", "ic/r-rad_sec")):
        if name in window:
            js[key] = float(window[name][0])
    return dataclasses.replace(tr, jsbsim=js)


def _fly(model: Model, start: Trim, window: FlightRecord, trimmed: dict[str, float],
         surfaces: tuple[str, ...], offsets: np.ndarray) -> tuple[FlightRecord, str | None]:
    """``window`` flown with its surfaces' increments on ``trimmed`` (rad) plus
    ``offsets`` on ``surfaces``."""
    t = window.time - window.time[0]
    rate = (len(t) - 1) / float(t[-1])
    off = dict(zip(surfaces, offsets, strict=True))
    controls = {s: window[s] - trimmed[s] + off.get(s, 0.0) for s in trimmed}
    try:
        return fly(model, start, controls, duration_s=float(t[-1]), rate_hz=rate,
                   surfaces="driven"), None
    except DepartureError as exc:
        return exc.record, str(exc)


def _residual(record: FlightRecord, flown: FlightRecord | None, outputs: tuple[str, ...],
              departed: bool) -> np.ndarray:
    n = len(record.time)
    out = []
    for ch in outputs:
        m = record[ch] - np.mean(record[ch])
        scale = float(np.std(m)) or 1.0
        s = np.full(n, np.nan)
        k = 0 if flown is None else min(n, len(flown.time))
        if k:
            s[:k] = flown[ch][:k] - np.mean(flown[ch][:k])
        r = (m - s) / scale
        r[np.isnan(r)] = DEPARTED if departed else 0.0
        out.append(r)
    return np.concatenate(out)


def fly_window(model: Model, tr: Trim, record: FlightRecord, window: FlightRecord,
               axis: str) -> WindowFlight:
    """``window`` (a window of ``record``) flown by ``model`` trimmed at ``tr``, with the
    offsets of the axis's surfaces refitted on it (``MAX_FLIGHTS`` flights). A lateral
    window is flown from its own start state (``start_state``); a longitudinal one from the
    record's start (its trim), through what comes before the window: the phugoid's state
    at the window's start (airspeed, height, the engine's) is the flight's history.

    Parameters
    ----------
    model : Model
        The loaded JSBSim aircraft (surfaces driven).
    tr : Trim
        Its trim where the record starts.
    record : FlightRecord
        The record.
    window : FlightRecord
        One of its windows.
    axis : str
        "lateral" or "longitudinal".

    Returns
    -------
    WindowFlight
        The gap per channel (residual over measured energy), the offsets (rad), the
        largest bank error (deg) and the departure, if any.
    """
    outputs = tuple(c for c in AXIS_OUTPUTS[axis] if c in window)
    surfaces = tuple(s for s in AXIS_INPUTS[axis] if s in window)
    if axis == "lateral":
        start, span = start_state(tr, record, window), window
    else:
        start, span = tr, record.slice(float(record.time[0]), float(window.time[-1]))
    lead = len(span.time) - len(window.time)  # samples flown before the window
    # the record's first sample is its trim: the surfaces are flown as increments on it
    trimmed = {s: float(record[s][0]) for s in ("da", "dr", "de") if s in window}

    def flown_window(x: np.ndarray) -> tuple[FlightRecord | None, str | None]:
        flown, departed = _fly(model, start, span, trimmed, surfaces, x)
        if len(flown.time) <= lead:
            return None, departed
        return flown.slice(float(flown.time[lead]), float(flown.time[-1])), departed

    def residual(x: np.ndarray) -> np.ndarray:
        flown, departed = flown_window(x)
        return _residual(window, flown, outputs, departed is not None)

    x = np.zeros(len(surfaces))
    if surfaces:
        fit = least_squares(residual, x, x_scale=OFFSET_SCALE, diff_step=1e-3,
                            bounds=(-OFFSET_LIMIT, OFFSET_LIMIT), max_nfev=MAX_FLIGHTS)
        x = fit.x
    flown, departed = flown_window(x)
    offsets = {s: float(v) for s, v in zip(surfaces, x, strict=True)}
    if flown is None:
        return WindowFlight({}, offsets, None, departed)
    n = len(flown.time)
    part = window.slice(float(window.time[0]), float(window.time[n - 1]))
    bank = None
    if axis == "lateral" and "phi" in window:
        bank = math.degrees(float(np.max(np.abs(flown["phi"] - window["phi"][:n]))))
    return WindowFlight(gap_fractions(part, flown, outputs), offsets, bank, departed)


def refly(result: Any, records: FlightRecord | list[FlightRecord], folder: str | Path,
          written: str | Path | None = None) -> dict[str, Any]:
    """The JSBSim shrink: the aircraft as is and the corrected one (``written``, else
    written now under ``folder``) flown on each maneuver window of every diagnosed axis
    (``fly_window``). Per window: the gap per channel before and after, the shrink, the
    surface offsets and the largest bank error; per axis and overall, the means over
    windows. A window where a model departs has no overall figure; it says so.

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    records : FlightRecord or list of FlightRecord
        Its records.
    folder : str or Path
        Where the corrected aircraft is written when ``written`` is None.
    written : str, Path or None
        The corrected aircraft's XML, when written already.

    Returns
    -------
    dict
        "aircraft", "windows" (per window: the gaps before and after per channel, offsets
        deg, bank errors deg, departures) and "overall" (before, after, shrink).
    """
    records = [records] if isinstance(records, FlightRecord) else list(records)
    path = Path(written) if written is not None else write_aircraft(result, folder)
    models = {"before": result.aircraft, "after": path}
    loaded = {k: load(str(augment_cached(str(m), [], CACHE, surface_drive=True)))
              for k, m in models.items()}
    trims: dict[tuple[str, int], Trim] = {}
    out: dict[str, Any] = {"aircraft": str(path), "windows": []}
    for axis in result.axes():
        for k, record in enumerate(records):
            for seg in segments([record], [f"record {k + 1}"], inputs=AXIS_INPUTS[axis]):
                out["windows"].append(_window_row(axis, k, seg.label, seg.record, loaded,
                                                  trims, record))
    done = [w["overall"] for w in out["windows"] if "overall" in w]
    if done:
        b = float(np.mean([d["before"] for d in done]))
        a = float(np.mean([d["after"] for d in done]))
        out["overall"] = {"before": b, "after": a, "shrink": _shrink(b, a)}
    return out


def _window_row(axis: str, k: int, label: str, window: FlightRecord,
                loaded: dict[str, Model], trims: dict[tuple[str, int], Trim],
                record: FlightRecord) -> dict[str, Any]:
    row: dict[str, Any] = {"axis": axis, "window": label, "record": k + 1}
    for key, model in loaded.items():
        if (key, k) not in trims:
            altitude, speed = start_condition(record)
            trims[(key, k)] = trim(model, max(altitude, 0.0), speed)
        w = fly_window(model, trims[(key, k)], record, window, axis)
        row[key] = w.gap
        row[f"{key}_offsets_deg"] = {s: math.degrees(v) for s, v in w.offsets.items()}
        row[f"{key}_bank_error_deg"] = w.bank_error_deg
        if w.departed:
            row[f"{key}_departed"] = w.departed
    if not any(f"{x}_departed" in row for x in loaded):
        row["channels"] = {c: {"before": row["before"][c], "after": row["after"][c],
                               "shrink": _shrink(row["before"][c], row["after"][c])}
                           for c in row["before"] if c in row["after"]}
        b, a = (float(np.nanmean(list(row[x].values()))) for x in loaded)
        row["overall"] = {"before": b, "after": a, "shrink": _shrink(b, a)}
    return row


def _shrink(before: float, after: float) -> float:
    return (before - after) / before if before > 0 else float("nan")
