"""The blind check's scoring of one case's diagnosis (``score``, ``CaseResult``): per axis
the verdict, whether the first named effect is in the injected one's class
(``classes``), its magnitude error, and the held-out gap before and after the named
effects (``run.run_case`` adds the null level).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.files import json_safe
from flightid.identification.gap import GapResult
from flightid.identification.gap.ranked import Ranked, mean_gap
from flightid.identification.gap.trim_level import TrimOffset
from flightid.scenarios.gap_benchmark import classes
from flightid.scenarios.gap_benchmark.cases import (
    AXES,
    BOTH,
    NULL,
    OUT,
    PAIR,
    Case,
    Effect,
)
from flightid.sim.effects.catalogue import CATALOGUE


def axis_result(result: GapResult, axis: str) -> GapResult | None:
    """The diagnosis of one axis (None when the axis was not diagnosed).

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    axis : str
        Axis name.

    Returns
    -------
    GapResult or None
        The axis's diagnosis.
    """
    return result.axes().get(axis)


def verdict(result: GapResult) -> str:
    """no_gap, explained, partly_unexplained or unexplained.

    Parameters
    ----------
    result : GapResult
        The diagnosis.

    Returns
    -------
    str
        The verdict.
    """
    return result.verdict


def _label(r: Ranked) -> str:
    return r.candidate.label


def _relative_error(effect: Effect, r: Ranked) -> float:
    """Mean over the injected (sized) parameters of |estimate - injected| / |injected -
    neutral| (|injected| for a neutral at infinity: a rate limit's); nan when the diagnosis
    gives none of them."""
    errors = []
    for name, injected in effect.magnitude.items():
        est = (r.parameters or {}).get(name)
        if est is None:
            continue
        neutral = CATALOGUE[effect.entry].parameter(name).zero
        value = float(est["value"]) if isinstance(est, dict) else float(est)
        if not math.isfinite(neutral):
            errors.append(abs(value - injected) / abs(injected))
        elif injected != neutral:
            errors.append(abs(value - injected) / abs(injected - neutral))
    return float(np.mean(errors)) if errors else math.nan


@dataclass
class CaseResult:
    """One case's diagnosis, scored (every field JSON-able: a study resumes from them)."""

    case: Case
    verdicts: dict[str, str] = field(default_factory=dict)  # per diagnosed axis
    named: dict[str, list[str]] = field(default_factory=dict)  # labels, per axis
    right: bool | None = None  # single: first named on its axis in its class
    all_named: bool | None = None  # pair: both effects named (any place, their axes)
    magnitude_error: float = math.nan  # single, named exactly: relative
    before: dict[str, float] = field(default_factory=dict)  # held-out gap, model as is
    after: dict[str, float] = field(default_factory=dict)  # after the named effects
    null: dict[str, float] = field(default_factory=dict)  # the null level per axis
    seconds: float = math.nan  # wall time
    cpu_seconds: float = math.nan  # this process's CPU time (one core)
    error: str = ""
    # named at trim level (``trim_level``), per axis: class -> entry(channel) value (rad)
    trim: dict[str, dict[str, str]] = field(default_factory=dict)
    # single: the first named or an effect listed as not told apart from it
    # (``rank.simplest``) in its class
    listed: bool | None = None

    @property
    def excess_shrink(self) -> float:
        """The shrink of the held-out gap above the null level, on the injected effects'
        axes where something is named (the smallest of them); nan when none."""
        out = []
        for axis, b in self.before.items():
            a, n = self.after.get(axis, math.nan), self.null.get(axis, math.nan)
            if all(math.isfinite(x) for x in (a, b, n)) and b > n:
                out.append((b - a) / (b - n))
        return min(out) if out else math.nan

    def to_json(self) -> dict[str, Any]:
        return {"case": self.case.to_json(), "label": self.case.label, "kind": self.case.kind,
                "verdicts": self.verdicts, "named": self.named, "trim": self.trim,
                "right": self.right, "listed": self.listed,
                "all_named": self.all_named, "magnitude_error": json_safe(self.magnitude_error),
                "before": self.before, "after": self.after, "null": self.null,
                "excess_shrink": json_safe(self.excess_shrink),
                "seconds": json_safe(self.seconds), "cpu_seconds": json_safe(self.cpu_seconds),
                "error": self.error}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CaseResult:
        nan = math.nan
        return cls(Case.from_json(d["case"]), d["verdicts"], d["named"], d["right"],
                   d["all_named"], nan if d["magnitude_error"] is None else d["magnitude_error"],
                   d["before"], d["after"], d["null"],
                   nan if d["seconds"] is None else d["seconds"],
                   nan if d.get("cpu_seconds") is None else d["cpu_seconds"], d["error"],
                   d.get("trim") or {}, d.get("listed"))


def _effect_axes(e: Effect) -> tuple[str, ...]:
    return AXES if e.axis == BOTH else (e.axis,)


def score(case: Case, result: GapResult) -> CaseResult:
    """``case`` scored from its diagnosis (the null level is filled in by ``run_case``).

    Parameters
    ----------
    case : Case
        The benchmark case.
    result : GapResult
        Its diagnosis.

    Returns
    -------
    CaseResult
        Verdicts and named effects per axis and the case's scores.
    """
    per_axis = {a: g for a in AXES if (g := axis_result(result, a)) is not None}
    out = CaseResult(case, {a: verdict(g) for a, g in per_axis.items()},
                     {a: [_label(r) for r in g.named] + ([g.line.label] if _line(g) else [])
                      for a, g in per_axis.items()})
    out.trim = {a: {o.label: f"{o.entry}({o.channel}) {o.value:+.5f} +- {o.bound:.5f}"
                    for o in g.trim if o.named} for a, g in per_axis.items()}
    if case.category == NULL:
        return out
    if case.category == PAIR:
        out.all_named = all(
            any(classes.same(e, p) for a in _effect_axes(e) if a in per_axis
                for r in per_axis[a].named for p in (_parts(r) if r.candidate.parts else [r]))
            or _at_trim(e, per_axis) is not None or _at_line(e, per_axis)
            for e in case.effects)
    elif case.category != OUT:
        e = case.effects[0]
        firsts = [per_axis[a].named[0] for a in _effect_axes(e)
                  if a in per_axis and per_axis[a].named]
        out.right = any(classes.same(e, r) for r in firsts)
        out.listed = out.right or any(classes.same(e, a) for r in firsts
                                      for a in r.alternatives)
        exact = [r for r in firsts if classes.exact(e, r)]
        if exact:
            out.magnitude_error = _relative_error(e, exact[0])
        elif _at_line(e, per_axis):  # its amplitude is seen after the anti-alias filter
            out.right = out.listed = True
        elif not firsts and (offset := _at_trim(e, per_axis)) is not None:
            # named at trim level only: the first thing the report names on its axes
            out.right = out.listed = True
            if offset.entry == e.entry and e.magnitude.get(offset.parameter):
                injected = e.magnitude[offset.parameter]
                out.magnitude_error = abs(offset.value - injected) / abs(injected)
    for e in case.effects:
        for a in _effect_axes(e):
            g = per_axis.get(a)
            if g is not None and g.named and g.named[0].heldout_before \
                    and g.named[-1].heldout_after:
                out.before[a] = mean_gap(g.named[0].heldout_before)
                out.after[a] = mean_gap(g.named[-1].heldout_after)
    return out


def _at_trim(effect: Effect, per_axis: dict[str, GapResult]) -> TrimOffset | None:
    """The trim-level offset named on ``effect``'s axes in one of its classes, or None."""
    names = classes.classes_of(effect)
    return next((o for a in _effect_axes(effect) if a in per_axis
                 for o in per_axis[a].trim if o.named and o.label in names), None)


def _line(g: GapResult) -> bool:
    return g.line is not None and g.line.named


def _at_line(effect: Effect, per_axis: dict[str, GapResult]) -> bool:
    """A spectral line (``identification.gap.lines``) named on ``effect``'s axes as its
    entry."""
    return any(_line(per_axis[a]) and per_axis[a].line.entry == effect.entry
               for a in _effect_axes(effect) if a in per_axis)


def _parts(r: Ranked) -> list[Any]:
    """The single effects of a named group, each as a Ranked-like view (the candidate and
    its parameters under the part's label)."""
    out = []
    for p in r.candidate.parts:
        prefix = f"{p.label}."
        params = {k[len(prefix):]: v for k, v in (r.parameters or {}).items()
                  if k.startswith(prefix)}
        out.append(_Part(p, params))
    return out


@dataclass
class _Part:
    candidate: Any
    parameters: dict[str, Any]
