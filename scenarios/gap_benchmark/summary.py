"""The blind check's figures, overall and per kind, against the targets of the design
(docs/gap_benchmark.md): in-catalogue single effects named right first and their median
magnitude error, null cases answered ``no_gap``, pairs with both effects named, effects
outside the catalogue answered ``unexplained`` or ``partly_unexplained``, and the median
held-out shrink of the gap above the null level where something is named."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from flightid.scenarios.gap_benchmark.cases import NULL, OUT, PAIR, SINGLE
from flightid.scenarios.gap_benchmark.scoring import CaseResult

# figure -> (target, whether higher is better)
TARGETS = {"right_first": (0.90, True), "magnitude_error": (0.05, False),
           "no_gap": (0.95, True), "both_named": (0.70, True),
           "unexplained": (0.85, True), "excess_shrink": (0.70, True)}
UNEXPLAINED = ("unexplained", "partly_unexplained")


def _frac(xs: list[bool]) -> float | None:
    return float(np.mean(xs)) if xs else None


def _median(xs: list[float]) -> float | None:
    xs = [x for x in xs if math.isfinite(x)]
    return float(np.median(xs)) if xs else None


def figures(results: list[CaseResult]) -> dict[str, Any]:
    """The six figures of ``results`` (None where no case counts) and the case counts.

    Parameters
    ----------
    results : list[CaseResult]
        The scored cases.

    Returns
    -------
    dict[str, Any]
        Case counts and the figures (fractions, or the median magnitude error).
    """
    flown = [r for r in results if not r.error]
    by = {c: [r for r in flown if r.case.category == c] for c in (SINGLE, PAIR, OUT, NULL)}
    # an outside effect's verdict is its own axis's
    axis_verdicts = [[r.verdicts[a] for a in (r.case.effects[0].axis,) if a in r.verdicts]
                     for r in by[OUT]]
    return {
        "cases": len(results), "failed": len(results) - len(flown),
        "single": len(by[SINGLE]), "pair": len(by[PAIR]), "outside": len(by[OUT]),
        "null": len(by[NULL]),
        "right_first": _frac([bool(r.right) for r in by[SINGLE]]),
        # no target: the injected effect named first or listed as not told apart from it
        "right_listed": _frac([bool(r.listed) for r in by[SINGLE]]),
        "magnitude_error": _median([r.magnitude_error for r in by[SINGLE]]),
        "no_gap": _frac([bool(r.verdicts) and all(v == "no_gap" for v in r.verdicts.values())
                         for r in by[NULL]]),
        "both_named": _frac([bool(r.all_named) for r in by[PAIR]]),
        "unexplained": _frac([any(v in UNEXPLAINED for v in vs) for vs in axis_verdicts]),
        # in the catalogue: an outside effect is not expected to close
        "excess_shrink": _median([r.excess_shrink for r in by[SINGLE] + by[PAIR]]),
        "seconds": float(sum(r.seconds for r in results if math.isfinite(r.seconds))),
        "cpu_seconds_median": _median([r.cpu_seconds for r in results]),
    }


def summary(results: list[CaseResult]) -> dict[str, Any]:
    """``figures`` overall, ``targets`` and whether each is met (``met``: None where no
    case counts), ``by_kind`` (the figures of each kind: an entry/axis, "pair" or "null"),
    and ``failed_cases`` (label: error).

    Parameters
    ----------
    results : list[CaseResult]
        The scored cases.

    Returns
    -------
    dict[str, Any]
        The summary, JSON-able.
    """
    overall = figures(results)
    met = {k: None if overall[k] is None else
           (overall[k] >= t if higher else overall[k] <= t)
           for k, (t, higher) in TARGETS.items()}
    kinds: dict[str, list[CaseResult]] = {}
    for r in results:
        kinds.setdefault(r.case.kind, []).append(r)
    return {**overall, "targets": {k: t for k, (t, _) in TARGETS.items()}, "met": met,
            "by_kind": {k: figures(v) for k, v in sorted(kinds.items())},
            "failed_cases": [f"{r.case.label}: {r.error}" for r in results if r.error]}
