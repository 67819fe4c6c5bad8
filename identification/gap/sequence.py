"""Effects named in sequence: the top effect fixed in the model, the rest ranked again.

One effect rarely explains a real gap alone, and a large one (a Dutch roll the model gets
wrong) masks the smaller ones: with it in the data, no single other effect can shrink the
held-out gap. So, after the top effect is confirmed, the model takes it at its fitted
values and the remaining candidates are fitted and checked on the held-out windows again
(forward selection; Morelli & Klein 2016 ch. 5.4 select regressors the same way), until
none is confirmed or ``STEPS`` effects are named. The held-out check of a later step uses
the earlier effects at their values fitted on all windows. How far the gap shrinks
(``shrinkage``): per channel, the held-out gap before and after the effects.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

from flightid.identification.gap.candidates.build import Candidate, catalogue_candidates
from flightid.identification.gap.candidates.linkage import is_linkage
from flightid.identification.gap.model.linearise import Linearised
from flightid.identification.gap.rank import Folds, Ranker, rank
from flightid.identification.gap.ranked import Ranked, mean_gap

STEPS = 3  # effects named at most


def fixed(lin: Linearised, effect: Ranked) -> Linearised:
    """``lin`` with ``effect`` added at its fitted values (no longer free).

    Parameters
    ----------
    lin : Linearised
        The model.
    effect : Ranked
        A named effect.

    Returns
    -------
    Linearised
    """
    model = effect.candidate.wrap(lin.model).with_start(**effect.values)
    return dataclasses.replace(lin, model=model)


def _taken(named: list[Ranked]) -> tuple[set[str], set[str]]:
    """(parameters already fitted, surfaces already scaled) by the named effects."""
    params: set[str] = set()
    surfaces: set[str] = set()
    for r in named:
        for c in r.candidate.parts or (r.candidate,):
            params.update(c.free)
            if c.entry == "control_effectiveness":
                surfaces.add(c.options["surface"])
    return params, surfaces


def _open(c: Candidate, params: set[str], surfaces: set[str]) -> bool:
    if is_linkage(c):  # a surface nonlinearity is no model edit (``candidates.linkage``)
        return False
    if set(c.free) & params:
        return False
    if c.entry == "control_effectiveness" and c.options["surface"] in surfaces:
        return False
    return not (c.entry == "derivative_delta"
                and c.options["derivative"].rpartition("_")[2] in surfaces)


def following(lin: Linearised, folds: Folds, first: Ranked, steps: int,
              at_null: Callable[[Linearised], bool] | None = None,
              above: Callable[[Linearised], dict[str, float]] | None = None) -> list[Ranked]:
    """Up to ``steps`` more effects after ``first``, each confirmed with the ones before it
    fixed in the model; stops at the first step that confirms nothing, or as soon as the
    model with the effects named so far passes ``at_null`` (its residual is at the null
    level of noise and turbulence: ``verdict.null_test``). ``above``: the gap above the
    null level of the model with the effects so far (``Ranker.above``).

    Parameters
    ----------
    lin : Linearised
        The model.
    folds : Folds
        The fitted and held-out windows.
    first : Ranked
        The first named effect (or pair).
    steps : int
        More effects at most.
    at_null : callable or None
        Whether a model is at the null level (stops the sequence).
    above : callable or None
        A model's gap above the null level per channel (what a next effect is judged against).

    Returns
    -------
    list of Ranked
        The effects named after ``first``, in order.
    """
    named = [first]
    current = fixed(lin, first)
    out: list[Ranked] = []
    for _ in range(max(steps, 0)):
        if at_null is not None and at_null(current):
            break
        params, surfaces = _taken(named)
        cands = [c for c in catalogue_candidates(current.model, current.axes,
                                                 surfaces=current.surfaces)
                 if _open(c, params, surfaces)]
        ranked = rank(Ranker(current, folds, above(current) if above else None), cands)
        if not ranked or not ranked[0].confirmed:
            break
        named.append(ranked[0])
        out.append(ranked[0])
        current = fixed(current, ranked[0])
    return out


def shrinkage(sequence: Sequence[Ranked]) -> dict:
    """{"effect", "steps", "channels": {ch: {"before", "after", "shrink"}}, "overall"}:
    the held-out gap (fraction of the measured energy) of the model as is (before the
    first effect) and with every effect of ``sequence`` (after the last), and the overall
    gap after each step; empty without an effect or held-out windows.

    Parameters
    ----------
    sequence : sequence of Ranked
        The named effects in order (each fitted with the ones before it fixed).

    Returns
    -------
    dict
        "effect" (the labels joined by "then"), "windows" (held out), "channels"
        {channel: before, after, shrink}, "steps" (each effect's held-out gap after it)
        and "overall" (mean over channels), as fractions of the measured energy; {}
        without an effect or held-out windows.
    """
    if not sequence or not sequence[0].heldout_before or not sequence[-1].heldout_after:
        return {}
    first, last = sequence[0], sequence[-1]
    chans = {}
    for ch, b in first.heldout_before.items():
        a = last.heldout_after[ch]
        chans[ch] = {"before": b, "after": a, "shrink": 1 - a / b if b > 0 else float("nan")}
    b, a = mean_gap(first.heldout_before), mean_gap(last.heldout_after)
    return {"effect": " then ".join(r.candidate.label for r in sequence),
            "windows": list(first.heldout_windows), "channels": chans,
            "steps": [{"effect": r.candidate.label, "after": mean_gap(r.heldout_after)}
                      for r in sequence],
            "overall": {"before": b, "after": a, "shrink": 1 - a / b if b > 0 else float("nan")}}


def shrink_text(x: float | None) -> str:
    """A shrink for a table: a percentage, "worse" when the gap grew, "-" when unknown.

    Parameters
    ----------
    x : float or None
        A relative shrink (1: the gap closed).

    Returns
    -------
    str
    """
    if x is None or not math.isfinite(x):
        return "-"
    return "worse" if x < 0 else f"{x:.0%}"
