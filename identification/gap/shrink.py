"""How far the gap shrinks: per channel, the held-out gap before and after the effects."""

from __future__ import annotations

import math
from collections.abc import Sequence

from flightid.identification.gap.rank import Ranked, overall


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
    b, a = overall(first.heldout_before), overall(last.heldout_after)
    return {"effect": " then ".join(r.candidate.label for r in sequence),
            "windows": list(first.heldout_windows), "channels": chans,
            "steps": [{"effect": r.candidate.label, "after": overall(r.heldout_after)}
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
