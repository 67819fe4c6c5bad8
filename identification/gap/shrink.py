"""How far the gap shrinks: per channel, the held-out gap before and after the effect."""

from __future__ import annotations

from flightid.identification.gap.rank import Ranked, overall


def shrinkage(r: Ranked | None) -> dict:
    """{"effect", "channels": {ch: {"before", "after", "shrink"}}, "overall": {...}}
    (fractions of the measured energy on the held-out windows); empty without a ranked
    effect or held-out windows."""
    if r is None or not r.heldout_before:
        return {}
    chans = {}
    for ch, b in r.heldout_before.items():
        a = r.heldout_after[ch]
        chans[ch] = {"before": b, "after": a, "shrink": 1 - a / b if b > 0 else float("nan")}
    b, a = overall(r.heldout_before), overall(r.heldout_after)
    return {"effect": r.candidate.label, "windows": list(r.heldout_windows), "channels": chans,
            "overall": {"before": b, "after": a, "shrink": 1 - a / b if b > 0 else float("nan")}}
