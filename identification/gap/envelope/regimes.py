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
3. **The trend** (``trend.trend``): each derivative that a ``derivative_delta`` names at some
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
   ``trend.TREND_SIGMAS`` of its bound names a ``derivative_table`` (delta_low at the lowest
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

from flightid.files import json_safe
from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.gap.diagnosis import GapResult, Records, _records, diagnose
from flightid.identification.gap.envelope.trend import Point, Trend, trend
from flightid.identification.gap.fit import fit
from flightid.identification.gap.model.linearise import record_condition
from flightid.identification.gap.ranked import combine, mean_gap
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
TREND_TOP = 3  # derivatives whose trend is fitted, in the order they were named


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
        return json_safe({
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
    return mean_gap(g.null_before.above()) if g.null_before is not None else math.nan


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
