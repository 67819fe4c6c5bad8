"""One blind case flown, diagnosed without being told and scored; the summary of many.

Each aircraft flies the same kind of lateral test (``cases.Flight``, ``SCHEDULE``: an
aileron doublet, a rudder 2-1-1, an aileron doublet and a rudder doublet, 44 s at 50 Hz,
research sensors corrected
to the CG (``DROPPED``), calm air: output error under turbulence is biased, docs/gap.md) with the
case's effect: airframe effects through
the card's ``[[effect]]`` (the augmented aircraft), a sensor ``scale`` and the effects
outside the catalogue applied to the measured record. The diagnosis
(``identification.gap.diagnose``) sees the record and the plain aircraft only.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.identification.gap import GapResult, diagnose
from flightid.identification.gap.linearise import linearise
from flightid.identification.gap.rank import Folds, Ranked, Ranker, overall, pooled_fractions
from flightid.identification.gap.segments import segments
from flightid.record import FlightRecord
from flightid.scenarios.cards import Card, card_from_dict, fly_card
from flightid.scenarios.gap_benchmark.cases import AIRCRAFT, Case, Flight
from flightid.scenarios.gap_benchmark.outside import OUTSIDE
from flightid.sim.condition import FlightCondition
from flightid.sim.model import load
from flightid.sim.trim import trim
from flightid.sim.truth import derivatives
from flightid.units import DEG

# (kind, surface, start s): each surface twice, 10-12 s apart (one window each)
# (an aileron 3211 banked the navion and the twin otter past 40 deg and changed their
# airspeed by 8 m/s: outside the lateral perturbation model; doublets leave 11-15 deg)
SCHEDULE = (("doublet", "da", 2.0), ("211", "dr", 12.0), ("doublet", "da", 22.0),
            ("doublet", "dr", 32.0))
DURATION_S = 44.0
RATE_HZ = 50.0
AIRFRAME = ("derivative_delta", "control_effectiveness")
TOP = 3  # top-k attribution
# sensor effects of the research suite the lateral model does not carry (vane position and
# upwash, accelerometer lever arm): air data and accelerations corrected to the CG first,
# as in a flight test's compatibility step and the navion-demo card
DROPPED = ("vanes", "lever_arm")


def _maneuver(kind: str, surface: str, start: float, f: Flight) -> dict[str, Any]:
    amplitude = f.aileron_deg if surface == "da" else f.rudder_deg
    return {"kind": kind, "surface": surface, "start": start, "base": f.base_s,
            "amplitude_deg": amplitude}


def card(aircraft: str, seed: int, effects: list[dict[str, Any]] | None = None) -> Card:
    """The lateral test card of ``aircraft`` with airframe ``effects``."""
    f = AIRCRAFT[aircraft]
    cond: dict[str, float] = {"altitude": f.altitude_m, "speed": f.speed_m_s}
    if f.flaps_deg:
        cond["flaps_deg"] = f.flaps_deg
    data: dict[str, Any] = {
        "name": f"gap-benchmark-{aircraft}", "aircraft": aircraft, "duration": DURATION_S,
        "rate": RATE_HZ, "seed": seed, "condition": cond,
        "maneuver": [_maneuver(kind, surface, start, f) for kind, surface, start in SCHEDULE],
        "sensors": {"suite": "research", "drop": list(DROPPED)}}
    if effects:
        data["effect"] = effects
    return card_from_dict(data, f"<gap-benchmark {aircraft}>")


def truths() -> dict[str, dict[str, float]]:
    """Each aircraft's body-axis derivatives at its test condition."""
    out = {}
    for name, f in AIRCRAFT.items():
        model = load(name)
        trimmed = trim(model, FlightCondition(f.altitude_m, f.speed_m_s,
                                              flaps_rad=f.flaps_deg * DEG))
        out[name] = dict(derivatives(model, trimmed, axes="body").values)
    return out


def fly_case(case: Case) -> FlightRecord:
    """The measured record of ``case`` (its effect injected)."""
    if case.entry in AIRFRAME:
        measured, _ = fly_card(card(case.aircraft, case.seed,
                                    [{"name": case.entry, **case.options, **case.magnitude}]))
        return measured
    measured, _ = fly_card(card(case.aircraft, case.seed))
    if case.entry == "scale":
        ch = case.options["channel"]
        return measured.with_channels(**{ch: measured[ch] * case.magnitude["factor"]})
    return OUTSIDE[case.entry](measured, **case.magnitude, **case.options)


def noise_floor(case: Case) -> float:
    """The held-out gap of the plain model on the plain flight of ``case``'s aircraft and
    seed (the same sensor noise): the part of a gap no effect can close."""
    plain, _ = fly_card(card(case.aircraft, case.seed))
    ranker = Ranker(linearise(case.aircraft, [plain]), Folds.make(segments([plain]), None))
    return overall(pooled_fractions(list(ranker.base_held.values())))


def _matches(case: Case, r: Ranked) -> bool:
    c = r.candidate
    if c.parts or c.entry != case.entry:
        return False
    return all(c.options.get(k) == v for k, v in case.options.items() if k != "axes")


def _relative_error(case: Case, r: Ranked) -> float:
    """|estimated - injected| / |injected change| of the case's magnitude."""
    name, injected = next(iter(case.magnitude.items()))
    estimated = r.parameters[name]["value"]
    change = injected if case.entry == "derivative_delta" else injected - 1.0
    return abs(estimated - injected) / abs(change)


@dataclass
class CaseResult:
    """One case's diagnosis, scored."""

    case: Case
    named: list[str]
    ranked: list[str]  # the first TOP of the ranking
    top1: bool
    top3: bool
    unexplained: bool
    shrink: float  # held-out shrink of the first named effect (nan: none named)
    floor: float  # held-out gap of the plain model on the plain flight (the noise)
    excess_shrink: float  # the shrink of the gap above the floor
    magnitude_error: float  # relative, of the matching ranked effect (nan: none)
    estimate: dict[str, dict[str, float]] = field(default_factory=dict)
    seconds: float = float("nan")
    error: str = ""
    partly: bool = False  # named effects leave part of the gap above the noise floor

    def to_json(self) -> dict[str, Any]:
        return {"case": self.case.to_json(), "label": self.case.label, "named": self.named,
                "ranked": self.ranked, "top1": self.top1, "top3": self.top3,
                "unexplained": self.unexplained, "shrink": _finite(self.shrink),
                "floor": _finite(self.floor), "excess_shrink": _finite(self.excess_shrink),
                "magnitude_error": _finite(self.magnitude_error), "estimate": self.estimate,
                "seconds": _finite(self.seconds), "error": self.error,
                "partly_unexplained": self.partly}


    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CaseResult:
        """Back from ``to_json`` (a line of ``cases.jsonl``)."""
        def num(x: float | None) -> float:
            return float("nan") if x is None else float(x)

        return cls(Case(**d["case"]), d["named"], d["ranked"], d["top1"], d["top3"],
                   d["unexplained"], num(d["shrink"]), num(d["floor"]),
                   num(d["excess_shrink"]), num(d["magnitude_error"]), d["estimate"],
                   num(d["seconds"]), d["error"], d.get("partly_unexplained", False))


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def score(case: Case, result: GapResult, floor: float = float("nan"),
          seconds: float = float("nan")) -> CaseResult:
    """``result`` (the diagnosis of ``case``'s record) against what was injected;
    ``floor``: the noise part of the gap (``noise_floor``)."""
    ranking: list[Ranked] = []
    for r in [*result.named[:1], *result.effects]:
        if all(r.candidate.label != o.candidate.label for o in ranking):
            ranking.append(r)
    top = ranking[:TOP]
    top1 = bool(case.in_catalogue and result.named and _matches(case, result.named[0]))
    top3 = bool(case.in_catalogue and any(_matches(case, r) for r in top))
    match = next((r for r in top if _matches(case, r)), None) if case.in_catalogue else None
    first = result.named[0] if result.named else None
    excess = float("nan")
    if first is not None and first.heldout_before:
        before, after = overall(first.heldout_before), overall(first.heldout_after)
        if before - floor > 1e-12:
            excess = (before - after) / (before - floor)
    return CaseResult(
        case=case, named=[r.candidate.label for r in result.named],
        ranked=[r.candidate.label for r in top], top1=top1, top3=top3,
        unexplained=result.unexplained,
        shrink=first.shrink if first is not None else float("nan"), floor=floor,
        excess_shrink=excess,
        magnitude_error=_relative_error(case, match) if match is not None else float("nan"),
        estimate=dict(match.parameters) if match is not None else {}, seconds=seconds,
        partly=result.partly_unexplained)


def run_case(case: Case, floor: bool = True, **options: Any) -> CaseResult:
    """Fly ``case``, diagnose it against the plain aircraft (``options``: of ``diagnose``,
    e.g. ``try_pairs``, ``steps``; the blind check uses its defaults), score it; with
    ``floor``, the noise floor of its flight too."""
    t0 = time.perf_counter()
    record = fly_case(case)
    result = diagnose([record], case.aircraft, **options)
    level = noise_floor(case) if floor else float("nan")
    return score(case, result, level, time.perf_counter() - t0)


def summary(results: list[CaseResult]) -> dict[str, Any]:
    """The fractions of the blind check: ``top1`` and ``top3`` (in-catalogue cases),
    ``shrinkage`` (median held-out shrink after the named effect, correctly named cases;
    ``excess_shrinkage`` the same of the gap above the noise floor),
    ``unexplained_correct`` (cases outside the catalogue reported unexplained, or partly
    unexplained: the named effects leave part of the gap above the noise floor). A case
    that could not be flown (it departed: the drawn effect made the aircraft unflyable
    open loop) is counted in ``failed`` and left out of the fractions."""
    flown = [r for r in results if not r.error]
    inside = [r for r in flown if r.case.in_catalogue]
    outside = [r for r in flown if not r.case.in_catalogue]
    right = [r for r in inside if r.top1]
    shrinks = [r.shrink for r in right if math.isfinite(r.shrink)]
    excess = [r.excess_shrink for r in right if math.isfinite(r.excess_shrink)]
    errors = [r.magnitude_error for r in inside if math.isfinite(r.magnitude_error)]

    def frac(xs: list[bool]) -> float | None:
        return float(np.mean(xs)) if xs else None

    by: dict[str, dict[str, Any]] = {}
    for r in inside:
        d = by.setdefault(r.case.entry, {"cases": 0, "top1": 0})
        d["cases"] += 1
        d["top1"] += int(r.top1)
    return {
        "cases": len(results), "in_catalogue": len(inside), "outside": len(outside),
        "failed": [f"{r.case.label}: {r.error}" for r in results if r.error],
        "top1": frac([r.top1 for r in inside]), "top3": frac([r.top3 for r in inside]),
        "shrinkage": float(np.median(shrinks)) if shrinks else None,
        "shrink_at_least_70": frac([s >= 0.7 for s in shrinks]),
        "excess_shrinkage": float(np.median(excess)) if excess else None,
        "excess_shrink_at_least_70": frac([s >= 0.7 for s in excess]),
        "magnitude_error_median": float(np.median(errors)) if errors else None,
        "unexplained_correct": frac([r.unexplained or r.partly for r in outside]),
        "false_unexplained": frac([r.unexplained for r in inside]),
        "false_partly_unexplained": frac([r.partly for r in right]),
        "by_entry": by,
        "seconds": float(sum(r.seconds for r in results if math.isfinite(r.seconds))),
    }
