"""Equivalence classes: candidates the data of one axis cannot tell apart.

A CG moved forward by x changes every pitching-moment derivative by its lift derivative
times x/cbar (``mass.cg_offset``); on the Navion, Cm_alpha moves by 4.4 x/cbar
while Cm_de and Cm_q move by under 1 % of their own values, so a ``cg_offset`` and a
``derivative_delta(Cm_alpha)`` are one class (and on the lateral axis a ``cg_offset`` and a
``derivative_delta(Cn_beta)``, through CY_beta x/b). On the Navion's elevator card a CG
shift of 0.1 m was fitted as x 0.1036 m or as a Cm_alpha delta of -0.249 (delta BIC 2 %
apart, held-out shrink 0.979 and 0.973), and a Cm_alpha delta of +0.1 was named a CG
shift until this rule. Within a class the
diagnosis names the model's own term, the derivative delta, unless the other member is
better on held-out data by the confirmation margin (``prefer_model_terms``); the other
classes are listed in docs/gap.md ("Equivalence classes").

The horizontal tail's effectiveness (``TAIL_CLASS``): on a record whose elevator moves in
a doublet and a 3211 of one amplitude, an elevator effectiveness factor, a Cm_de delta,
tail ice and an elevator play are not told apart (the blind check's development seeds:
docs/gap_benchmark.md, "The rules for the seed-9 run"): a named member is reported as the
class, "horizontal-tail effectiveness -20 %" (``class_text``); likewise a surface's
actuator lag and rate limit on a record of commands.
"""

from __future__ import annotations

import math
from typing import Any

from flightid.identification.gap.model.edits import Candidate

# entry -> the derivatives whose delta is its class's member named first
CLASS_OF: dict[str, tuple[str, ...]] = {"cg_offset": ("Cm_alpha", "Cn_beta")}


def same_class(a: Candidate, b: Candidate) -> bool:
    """Whether ``a`` and ``b`` are one of the classes of ``CLASS_OF`` (either order).

    Parameters
    ----------
    a, b : Candidate
        Two candidates.

    Returns
    -------
    bool
    """
    for x, y in ((a, b), (b, a)):
        if (x.entry in CLASS_OF and y.entry == "derivative_delta"
                and y.options.get("derivative") in CLASS_OF[x.entry]):
            return True
    return False


def prefer_model_terms(ranked: list[Any], margin: float) -> None:
    """Unconfirm a confirmed member of a class (``CLASS_OF``) when a confirmed derivative
    delta of its class leaves a held-out gap within ``margin`` (relative) of its own: the
    data cannot tell them apart, and the delta is the model's own term. ``ranked``: the
    ``ranked.Ranked`` of one ranking.

    Parameters
    ----------
    ranked : list of Ranked
        The ranked effects, changed in place.
    margin : float
        Relative held-out margin by which a class member must beat the delta.
    """
    confirmed = [r for r in ranked if r.confirmed and r.heldout_after]
    for r in confirmed:
        if r.candidate.entry not in CLASS_OF:
            continue
        for d in confirmed:
            if d.candidate.entry == "derivative_delta" and same_class(r.candidate, d.candidate):
                mine, theirs = _gap(r), _gap(d)
                if mine > (1 - margin) * theirs:
                    r.confirmed = False
                    r.note = (f"one class with {d.candidate.label} (not better on held-out "
                              "data): the model's own term is named")
                    break


def _gap(r: Any) -> float:
    known = [v for v in r.heldout_after.values() if v == v]
    return sum(known) / len(known) if known else float("nan")


TAIL_CLASS = "horizontal-tail effectiveness"
TAIL_MEMBERS = ("elevator effectiveness", "Cm_de", "tail ice", "elevator play")


def class_text(ranked: Any, start: dict[str, float]) -> str:
    """A named effect of ``TAIL_CLASS`` in the class's words, with the change of the tail's
    effectiveness in percent where the member gives one, or a surface's lag or rate limit
    as its class ("" for any other effect).

    Parameters
    ----------
    ranked : Ranked
        A named effect (``ranked.Ranked``: its candidate and catalogue parameters).
    start : dict of str to float
        The model's values (the Cm_de that a delta is relative to).

    Returns
    -------
    str
        E.g. "horizontal-tail effectiveness -20 % (one class on these maneuvers:
        elevator effectiveness, Cm_de, tail ice, elevator play)", or "".
    """
    c = ranked.candidate
    value = {k: v["value"] for k, v in (ranked.parameters or {}).items()}
    members = f"(one class on these maneuvers: {', '.join(TAIL_MEMBERS)})"
    change = math.nan
    if c.entry == "control_effectiveness" and c.options.get("surface") == "de":
        change = value["factor"] - 1.0
    elif c.entry == "derivative_delta" and c.options.get("derivative") == "Cm_de":
        base = start.get("Cm_de", math.nan)
        change = value["delta"] / base if base else math.nan
    elif c.entry == "tail_ice":
        change = value["elevator"] - 1.0
    elif c.entry in ("actuator_lag", "rate_limit"):
        return (f"actuator lag or rate limit of {c.options.get('surface')} (one class on "
                "these maneuvers)")
    elif c.entry == "backlash" and c.options.get("surface") == "de":
        return (f"{TAIL_CLASS} or elevator play {math.degrees(value['width']):.2f} deg "
                f"{members}")
    else:
        return ""
    return f"{TAIL_CLASS} {100 * change:+.0f} % {members}"


def surface_before_inertia(first: Any, group: list[Any]) -> Any:
    """The effect named among ``group`` (confirmed effects the held-out data cannot tell
    apart, ``rank.tied``), given the one chosen by fewest parameters, ``first``: when that is
    an inertia scale and a surface's effect (an entry with a ``surface`` option: its
    effectiveness, lag, rate limit, play, ...) of as many parameters is in the group, the
    surface's. An inertia k divides every moment derivative about its axis, so it slows the
    response as a surface's lag does and takes the surface's power with the rest; the
    surface's effect is the narrower explanation (on seed 9 of the blind check the inertia
    scale was tied with and named before an elevator lag and an elevator effectiveness:
    docs/gap_benchmark.md, "The rules for the seed-10 run").

    Parameters
    ----------
    first : Ranked
        The effect chosen so far.
    group : list of Ranked
        The tied confirmed effects, ``first`` among them, in ranking order.

    Returns
    -------
    Ranked
        ``first``, or the first surface effect of the group with as many free parameters.
    """
    if first.candidate.entry != "inertia_scale":
        return first
    n = len(first.candidate.free)
    return next((r for r in group if "surface" in r.candidate.options
                 and len(r.candidate.free) == n), first)
