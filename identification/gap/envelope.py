"""The gap across the envelope: records flown at several conditions, each condition
diagnosed against the model linearised there, and a derivative error that changes with
the condition named as such, with its trend (the catalogue's ``derivative_table``).

1. **Conditions** (``conditions``): the records grouped by their mean true airspeed
   (within ``SPEED_TOL``), altitude (within ``ALTITUDE_TOL``) and flap deflection (channel
   ``df`` or ``meta.condition["flaps"]``, within ``FLAPS_TOL``). A linearised model holds at
   one condition only: the records of each group are diagnosed together
   (``diagnose.diagnose``), against the model trimmed at that group's condition.
2. **Where in the envelope** (``regime_bins``): the conditions sorted by airspeed, by the
   model's trim angle of attack there and by flaps (where they vary), in up to
   ``REGIME_BINS`` equal-count bins; per bin and axis, the verdicts and the gap above the
   null level (the null test's input-explained share less chance, mean over the
   channels, ``verdict.NullTest.above``) of the model as is.
3. **The trend** (``trend``): each derivative that a ``derivative_delta`` names at some
   condition is fitted at *every* condition (output error on that condition's windows,
   the rest of its model held; ``fit.fit``), so that the conditions without a gap give
   their (near-zero) delta too. The deltas are fitted with a straight line in the airspeed
   (m/s) and in the trim alpha (rad) by weighted least squares, weights the inverse
   variances of the points' Cramer-Rao bounds, the covariance scaled by the reduced
   chi-square when it exceeds one (the Birge ratio: the points scatter beyond their
   bounds; Bevington & Robinson 2003 sec. 6.5). The schedule whose line leaves the lower
   chi-square is kept. In level flight at one altitude and weight, airspeed and alpha
   move together (alpha ~ 1/V^2), so the two schedules are one equivalence class there;
   flights at another weight or altitude separate them. A slope of more than
   ``TREND_SIGMAS`` of its bound names a ``derivative_table`` (delta_low at the lowest
   flown condition, delta_high at the highest: the catalogue's parameters); otherwise the
   derivative error is one ``derivative_delta``, the same at every condition (the
   inverse-variance mean). The table must leave the derivative inside its physical range
   at every condition (``ranges.out_of_range``); else the range note says what fits.
   One condition: the trend is not identifiable, and the delta of that condition is
   the diagnosis's ``derivative_delta``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flightid.identification.gap.candidates.ranges import derivative_outside
from flightid.identification.gap.diagnose import GapResult, Records, _finite, _records, diagnose
from flightid.identification.gap.fit import fit
from flightid.identification.gap.model.linearise import AXIS_INPUTS, record_condition
from flightid.identification.gap.rank import combine, overall
from flightid.identification.gap.segments import segments, split
from flightid.identification.gap.sequence import STEPS
from flightid.identification.gap.verdict import worst
from flightid.record import FlightRecord
from flightid.sim.augment import augment
from flightid.sim.effects.airframe import AugmentEffect, DerivativeDelta, DerivativeTable

SPEED_TOL = 0.03  # records within 3 % of each other's mean airspeed: one condition
ALTITUDE_TOL = 150.0  # m
FLAPS_TOL = math.radians(1.0)  # rad
REGIME_BINS = 3  # bins of conditions per regime variable (each condition its own up to 3)
TREND_SIGMAS = 3.0  # a slope beyond this many of its bound is a trend
TREND_TOP = 3  # derivatives whose trend is fitted, in the order they were named
SCHEDULES = {"airspeed": ("m/s", 1.0), "alpha": ("deg", 180.0 / math.pi)}  # unit, scale


@dataclass
class Condition:
    """The records flown at one condition."""

    label: str
    records: list[FlightRecord]
    names: list[str]
    speed_m_s: float  # mean true airspeed of the records
    altitude_m: float
    flaps_rad: float | None  # mean flap deflection; None when not recorded

    def to_json(self) -> dict[str, Any]:
        return {"label": self.label, "records": self.names, "speed_m_s": self.speed_m_s,
                "altitude_m": self.altitude_m, "flaps_deg": None if self.flaps_rad is None
                else math.degrees(self.flaps_rad)}


def _flaps(record: FlightRecord) -> float | None:
    if "df" in record:
        return float(np.mean(record["df"]))
    cond = record.meta.condition or {}
    return float(cond["flaps"]) if "flaps" in cond else None


def conditions(records: Sequence[FlightRecord], names: Sequence[str]) -> list[Condition]:
    """The records grouped by condition (module docstring, step 1).

    Parameters
    ----------
    records : sequence of FlightRecord
        The records, each with its airspeed V (m/s) and altitude h (m) as channels or in
        ``meta.condition``.
    names : sequence of str
        Their labels, same order.

    Returns
    -------
    list of Condition
        Sorted by airspeed, each labelled by its airspeed and altitude.
    """
    groups: list[list[int]] = []
    keys = [(*record_condition(r)[::-1], _flaps(r)) for r in records]  # (V, h, flaps)
    for k, (v, h, f) in enumerate(keys):
        for g in groups:
            v0, h0, f0 = keys[g[0]]
            if (abs(v - v0) <= SPEED_TOL * v0 and abs(h - h0) <= ALTITUDE_TOL
                    and (f is None) == (f0 is None)
                    and (f is None or abs(f - f0) <= FLAPS_TOL)):
                g.append(k)
                break
        else:
            groups.append([k])
    out = []
    for g in groups:
        v = float(np.mean([keys[k][0] for k in g]))
        h = float(np.mean([keys[k][1] for k in g]))
        flaps = [keys[k][2] for k in g if keys[k][2] is not None]
        f = float(np.mean(flaps)) if flaps else None
        label = f"{v:.1f} m/s, {h:.0f} m" + (f", flaps {math.degrees(f):.0f} deg"
                                              if f is not None and abs(f) > FLAPS_TOL else "")
        out.append(Condition(label, [records[k] for k in g], [names[k] for k in g], v, h, f))
    return sorted(out, key=lambda c: (c.speed_m_s, c.altitude_m))


@dataclass
class Point:
    """One condition's fitted delta of a derivative (the model's axes at that condition)."""

    condition: str
    speed_m_s: float  # the condition's trim airspeed
    alpha: float  # the model's trim alpha there, rad
    model: float  # the model's derivative there
    delta: float
    std: float

    def to_json(self) -> dict[str, Any]:
        return {"condition": self.condition, "speed_m_s": self.speed_m_s,
                "alpha_deg": math.degrees(self.alpha), "model": self.model,
                "delta": self.delta, "std": self.std}


@dataclass
class Line:
    """delta = level + slope (x - center), fitted by weighted least squares."""

    schedule: str  # "airspeed" (x in m/s) or "alpha" (x in rad)
    center: float
    level: float
    level_std: float
    slope: float  # per m/s or per rad
    slope_std: float
    chi2: float  # weighted residual sum of squares of the points about the line
    scaled: float  # the factor the bounds were scaled by (1, or sqrt of the reduced chi2)

    def at(self, x: float) -> float:
        return self.level + self.slope * (x - self.center)


def line(x: np.ndarray, y: np.ndarray, std: np.ndarray, schedule: str) -> Line:
    """The weighted straight line through the points (module docstring, step 3).

    Parameters
    ----------
    x : ndarray
        The schedule's values (m/s, or rad for alpha).
    y, std : ndarray
        The deltas and their bounds (per rad, or per unit nondimensional rate).
    schedule : str
        "airspeed" or "alpha".

    Returns
    -------
    Line
        Level at the weighted mean x and slope (per m/s or per rad), with bounds scaled
        by the Birge ratio where the points scatter beyond theirs; with two points,
        exactly through them, its bounds from theirs.
    """
    w = 1.0 / std**2
    center = float(np.sum(w * x) / np.sum(w))
    X = np.column_stack([np.ones_like(x), x - center])
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    beta = cov @ X.T @ (w * y)
    chi2 = float(np.sum(w * (y - X @ beta) ** 2))
    dof = x.size - 2
    scale = math.sqrt(chi2 / dof) if dof > 0 and chi2 > dof else 1.0
    return Line(schedule, center, float(beta[0]), scale * math.sqrt(cov[0, 0]),
                float(beta[1]), scale * math.sqrt(cov[1, 1]), chi2, scale)


@dataclass
class Trend:
    """A derivative's delta across the conditions, and the catalogue effect it names."""

    axis: str
    derivative: str
    axes: str  # of the delta: the axis's model axes (body lateral, stability longitudinal)
    points: list[Point]
    lines: dict[str, Line] = field(default_factory=dict)  # per schedule
    schedule: str = ""  # the kept line's ("" with one point)
    # the named effect in the catalogue's units: {"name", "options", "parameters"}
    effect: dict[str, Any] = field(default_factory=dict)
    note: str = ""  # outside the physical range, or why no trend
    mean: float = math.nan  # the inverse-variance mean delta
    mean_std: float = math.nan

    @property
    def line(self) -> Line | None:
        return self.lines.get(self.schedule)

    @property
    def significant(self) -> bool:
        """The kept line's slope is beyond ``TREND_SIGMAS`` of its bound."""
        ln = self.line
        return ln is not None and abs(ln.slope) > TREND_SIGMAS * ln.slope_std

    def slope_text(self) -> str:
        """'-0.00118 +- 0.00004 per m/s' (alpha: per deg)."""
        ln = self.line
        if ln is None:
            return "one condition: no trend"
        unit, scale = SCHEDULES[ln.schedule]
        return f"{ln.slope / scale:+.3g} ± {ln.slope_std / scale:.2g} per {unit}"

    def label(self) -> str:
        e = self.effect
        opts = ",".join(str(v) for v in e.get("options", {}).values())
        return f"{e.get('name', '?')}({opts})"

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "axis": self.axis, "derivative": self.derivative, "axes": self.axes,
            "points": [p.to_json() for p in self.points], "schedule": self.schedule or None,
            "named": self.effect, "significant": self.significant, "note": self.note or None,
            "mean": {"value": self.mean, "std": self.mean_std}, "lines": {}}
        for s, ln in self.lines.items():
            unit, scale = SCHEDULES[s]
            out["lines"][s] = {"slope": ln.slope / scale, "slope_std": ln.slope_std / scale,
                               "unit": f"per {unit}", "level": ln.level,
                               "level_std": ln.level_std, "at": ln.center * scale,
                               "chi2": ln.chi2, "bounds_scaled_by": ln.scaled}
        return out


def _x(point: Point, schedule: str) -> float:
    return point.speed_m_s if schedule == "airspeed" else point.alpha


def trend(axis: str, derivative: str, axes: str, points: list[Point]) -> Trend:
    """The trend of ``derivative``'s delta over ``points`` and the effect it names
    (module docstring, step 3).

    Parameters
    ----------
    axis : str
        "lateral" or "longitudinal": the axis whose model the deltas are fitted on.
    derivative : str
        The derivative, e.g. "Cn_beta".
    axes : str
        Axes of the deltas: "body" (lateral) or "stability" (longitudinal).
    points : list of Point
        One per condition.

    Returns
    -------
    Trend
        The lines in airspeed and alpha, the schedule kept, and the catalogue effect
        named (``derivative_table`` when the slope is beyond ``TREND_SIGMAS`` bounds,
        else ``derivative_delta``), with a note when outside the physical range.
    """
    out = Trend(axis, derivative, axes, points)
    d = np.array([p.delta for p in points])
    s = np.array([p.std for p in points])
    w = 1.0 / s**2
    out.mean, out.mean_std = float(np.sum(w * d) / np.sum(w)), float(1.0 / math.sqrt(np.sum(w)))
    options = {"derivative": derivative, "axes": axes}
    if len(points) >= 2:
        for schedule in SCHEDULES:
            x = np.array([_x(p, schedule) for p in points])
            if np.ptp(x) > 0:
                out.lines[schedule] = line(x, d, s, schedule)
    if out.lines:  # the schedule whose line fits the points better (airspeed on a tie)
        out.schedule = min(out.lines, key=lambda k: (out.lines[k].chi2, k != "airspeed"))
    if out.significant:
        ln = out.line
        xs = [_x(p, out.schedule) for p in points]
        lo, hi = min(xs), max(xs)
        out.effect = {"name": "derivative_table",
                      "options": {**options, "schedule": out.schedule},
                      "parameters": {"delta_low": ln.at(lo), "delta_high": ln.at(hi),
                                     "low": lo, "high": hi}}
        deltas = [(p, ln.at(_x(p, out.schedule))) for p in points]
    else:
        out.effect = {"name": "derivative_delta", "options": options,
                      "parameters": {"delta": {"value": out.mean, "std": out.mean_std}}}
        out.note = ("one condition: the trend is not identifiable; records at other "
                    "airspeeds or alphas make it so" if len(points) < 2 else
                    f"no trend: slope {out.slope_text()}, within {TREND_SIGMAS:g} bounds")
        deltas = [(p, out.mean) for p in points]
    ranges = [_outside(derivative, p, v) for p, v in deltas]
    if found := [r for r in ranges if r]:
        out.note = "outside its physical range: " + "; ".join(found)
    return out


def _outside(derivative: str, point: Point, delta: float) -> str | None:
    found = derivative_outside(derivative, point.model + delta)
    return f"at {point.condition}: {found}" if found else None


@dataclass
class EnvelopeResult:
    """The diagnosis of records from several conditions (module docstring)."""

    aircraft: str
    conditions: list[Condition]
    results: list[GapResult]  # per condition, same order
    trends: list[Trend] = field(default_factory=list)
    bins: list[dict[str, Any]] = field(default_factory=list)

    @property
    def verdict(self) -> str:
        """The most severe verdict of the conditions."""
        return worst([r.verdict for r in self.results])

    @property
    def named(self) -> list[Trend]:
        """The trends that name a condition-dependent error (a ``derivative_table``)."""
        return [t for t in self.trends if t.effect.get("name") == "derivative_table"
                and not t.note]

    def to_json(self) -> dict[str, Any]:
        return _finite({
            "aircraft": self.aircraft, "verdict": self.verdict,
            "conditions": [{**c.to_json(), "verdict": r.verdict,
                            "axes": {a: {"verdict": g.verdict,
                                         "above_null": _above(g),
                                         "named": [x.candidate.label for x in g.named]}
                                     for a, g in r.axes().items()}}
                           for c, r in zip(self.conditions, self.results, strict=True)],
            "regimes": self.bins,
            "trends": [t.to_json() for t in self.trends]})


def _above(g: GapResult) -> float:
    """The gap above the null level of the model as is: mean over channels of the null
    test's input-explained share less chance (nan without a test)."""
    return overall(g.null_before.above()) if g.null_before is not None else math.nan


def regime_bins(conds: list[Condition], results: list[GapResult]) -> list[dict[str, Any]]:
    """Where in the envelope the model departs.

    Parameters
    ----------
    conds : list of Condition
        The conditions.
    results : list of GapResult
        Their diagnoses, same order.

    Returns
    -------
    list of dict
        Per regime variable (airspeed m/s, the model's trim alpha deg, flaps deg where
        they vary), bin of conditions (up to ``REGIME_BINS``, equal count) and diagnosed
        axis: "variable", "unit", "low", "high", "axis", "conditions", "verdicts" and
        "above_null" (their mean gap above the null level, a fraction of the measured
        energy).
    """
    rows: list[dict[str, Any]] = []
    alphas = [next(iter(r.axes().values())).linearised.trim.alpha for r in results]
    values = {"airspeed": ("m/s", [c.speed_m_s for c in conds]),
              "alpha": ("deg", [math.degrees(a) for a in alphas])}
    if all(c.flaps_rad is not None for c in conds):
        values["flaps"] = ("deg", [math.degrees(c.flaps_rad) for c in conds])  # type: ignore[arg-type]
    for var, (unit, xs) in values.items():
        if np.ptp(xs) <= 0:
            continue
        order = np.argsort(xs, kind="stable")
        for part in np.array_split(order, min(REGIME_BINS, len(conds))):
            members = [int(i) for i in part]
            axes = dict.fromkeys(a for i in members for a in results[i].axes())
            for axis in axes:
                gs = [results[i].axes()[axis] for i in members if axis in results[i].axes()]
                rows.append({"variable": var, "unit": unit,
                             "low": float(min(xs[i] for i in members)),
                             "high": float(max(xs[i] for i in members)),
                             "axis": axis, "conditions": [conds[i].label for i in members],
                             "verdicts": [g.verdict for g in gs],
                             "above_null": float(np.nanmean([_above(g) for g in gs]))})
    return rows


def _named_derivatives(results: list[GapResult]) -> list[tuple[str, str, str]]:
    """(axis, derivative, axes) of every ``derivative_delta`` named at some condition, in
    the order named (a pair's parts included)."""
    found: list[tuple[str, str, str]] = []
    for r in results:
        for axis, g in r.axes().items():
            for ranked in g.named:
                for c in ranked.candidate.parts or (ranked.candidate,):
                    if c.entry == "derivative_delta":
                        found.append((axis, c.options["derivative"], c.options["axes"]))
    return list(dict.fromkeys(found))[:TREND_TOP]


def point(cond: Condition, g: GapResult, derivative: str) -> Point | None:
    """``derivative``'s delta at one condition.

    Parameters
    ----------
    cond : Condition
        The condition and its records.
    g : GapResult
        Its diagnosis on one axis (its linearised model).
    derivative : str
        The derivative freed, e.g. "Cn_beta".

    Returns
    -------
    Point or None
        Output error on each of the condition's windows of the axis (a single window
        cut in halves), the rest of the model held, the windows' inverse-variance mean;
        None when no window identifies it.
    """
    lin = g.linearised
    if derivative not in lin.model.parameters:
        return None
    wins = segments(cond.records, cond.names, AXIS_INPUTS[lin.axis])
    if len(wins) == 1:
        wins = split(wins[0])
    fits = []
    for s in wins:
        try:
            fits.append(fit(lin.model, s.record, (derivative,)))
        except (ValueError, np.linalg.LinAlgError):
            continue
    both = combine(fits, (derivative,)) if fits else None
    if both is None:
        return None
    value, std = both[0][derivative], both[1][derivative]
    model = float(lin.model.start[derivative])
    return Point(cond.label, float(lin.trim.speed_m_s), float(lin.trim.alpha), model,
                 value - model, std)


def envelope(records: Records, aircraft: str, names: Sequence[str] | None = None,
             axis: str = "both", try_pairs: bool = True, steps: int = STEPS,
             surfaces: str | None = None) -> EnvelopeResult:
    """Diagnose ``records`` flown at several conditions against ``aircraft``: each
    condition on its own (``diagnose``), where in the envelope the model departs
    (``regime_bins``), and the trend of every derivative error named (``trend``).

    Parameters
    ----------
    records : flight records (or paths) of one aircraft, at one or more conditions.
    aircraft : JSBSim aircraft (project name, stock name or XML path).
    names : the records' labels (default: file stems, or "record k").
    axis, try_pairs, steps, surfaces : as ``diagnose``, for each condition.

    Returns
    -------
    EnvelopeResult
        Per condition its ``GapResult``; the regime bins; per named derivative its
        points and trend, and the catalogue effect it names (``derivative_table`` with
        its parameters in catalogue units, or ``derivative_delta``).
    """
    recs, found = _records(records)
    labels = list(names) if names else found
    conds = conditions(recs, labels)
    results = [diagnose(c.records, aircraft, names=c.names, axis=axis, try_pairs=try_pairs,
                        steps=steps, surfaces=surfaces) for c in conds]
    trends = []
    for ax, derivative, axes in _named_derivatives(results):
        pts = [p for c, r in zip(conds, results, strict=True) if ax in r.axes()
               and (p := point(c, r.axes()[ax], derivative)) is not None]
        if pts:
            trends.append(trend(ax, derivative, axes, pts))
    return EnvelopeResult(str(aircraft), conds, results, trends, regime_bins(conds, results))


def trend_effects(result: EnvelopeResult) -> list[AugmentEffect]:
    """The catalogue effects the trends name inside their physical range.

    Parameters
    ----------
    result : EnvelopeResult
        The diagnosis across the conditions.

    Returns
    -------
    list of AugmentEffect
        A ``DerivativeTable`` per trend, a ``DerivativeDelta`` per derivative without one.
    """
    out: list[AugmentEffect] = []
    for t in result.trends:
        if t.note and not t.note.startswith("no trend"):
            continue
        e = t.effect
        p = {k: (v["value"] if isinstance(v, dict) else v) for k, v in e["parameters"].items()}
        cls = DerivativeTable if e["name"] == "derivative_table" else DerivativeDelta
        out.append(cls(**e["options"], **p, source="flightid gap"))
    return out


def write_envelope_aircraft(result: EnvelopeResult, folder: str | Path,
                            name: str | None = None) -> Path:
    """Write ``result.aircraft`` with the effects its trends name (``trend_effects``).

    Parameters
    ----------
    result : EnvelopeResult
        The diagnosis across the conditions.
    folder : str or Path
        Where the aircraft folder is written (``sim.augment``).
    name : str or None
        The new aircraft's name (default: "<aircraft>-corrected").

    Returns
    -------
    Path
        The new XML. Raises ValueError when no trend names an effect in range.
    """
    effects = trend_effects(result)
    if not effects:
        raise ValueError("the diagnosis across the conditions named no derivative error "
                         "inside its physical range: nothing to write")
    stem = Path(str(result.aircraft)).stem
    return augment(result.aircraft, effects, folder, name=name or f"{stem}-corrected")
