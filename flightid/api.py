"""The public API: ``fly``, ``identify``, ``score``, ``truth``, ``methods``, ``effects``.

    import flightid
    flight = flightid.fly("navion-demo", seed=1)
    est = flightid.identify(flight.measured, method="oe", model="lon")
    print(flightid.score(est, flight.truth).verdict)

Every command of the command line is a thin call of these functions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flightid.identification.evaluation.scoring import Score, record_truth, score
from flightid.identification.gap import diagnose as gap
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.identification.methods.protocol import Method
from flightid.record import FlightRecord
from flightid.scenarios.cards import Card, fly_card, load_card
from flightid.scenarios.gap_benchmark import benchmark as gap_benchmark
from flightid.scenarios.gym import ENV_ID as EXCITATION_ENV  # registers it with gymnasium
from flightid.scenarios.montecarlo import run as montecarlo
from flightid.scenarios.montecarlo.design_report import compare_and_report as design_compare
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.sim.jsbsim.truth import Truth, derivatives

__all__ = ["EXCITATION_ENV", "Flight", "fly", "gap", "identify", "methods", "montecarlo", "score",
           "truth", "gap_benchmark"]
__all__ += ["design_compare"]  # design.compare + its PNG/HTML report (docs/montecarlo.md)


@dataclass
class Flight:
    """One simulated flight of a card: what the sensors recorded and what really happened.

    measured: the record through the card's sensors (what a method sees); truth_record:
    the same flight without sensors; truth: the exact derivatives in the body axes of the
    identification models (per rad, rates nondimensional); truth_stability: the same in
    stability axes; trim: the trimmed start; maneuvers: [{"kind", "surfaces", "start",
    "end"}] (s); a_priori: the card's a priori values {name: {"value", "std", "source"}}.
    """

    card: Card
    seed: int
    measured: FlightRecord
    truth_record: FlightRecord
    truth: dict[str, float]
    truth_stability: dict[str, float]
    trim: Trim | None
    maneuvers: list[dict[str, Any]] = field(default_factory=list)
    a_priori: dict[str, dict[str, Any]] = field(default_factory=dict)


def fly(card: str | Path | Card, seed: int | None = None) -> Flight:
    """Fly a flight card (a library name such as "navion-demo", a TOML path, or a Card)
    with ``seed`` (default: the card's) in JSBSim; a pure function of card and seed."""
    c = card if isinstance(card, Card) else load_card(card)
    used = c.seed if seed is None else int(seed)
    measured, truth_record = fly_card(c, used)
    table = truth_record.meta.extra.get("truth") or {}
    return Flight(
        card=c, seed=used, measured=measured, truth_record=truth_record,
        truth=record_truth(truth_record), truth_stability=dict(table.get("stability") or {}),
        trim=Trim(**table["trim"]) if "trim" in table else None,
        maneuvers=list(truth_record.meta.extra.get("maneuvers") or []),
        a_priori=dict(truth_record.meta.extra.get("a_priori") or {}),
    )


def truth(aircraft: str, altitude: float, speed: float, *, gamma: float = 0.0,
          bank: float = 0.0, flaps: float = 0.0, axes: str = "body",
          propulsion: bool = False) -> Truth:
    """Exact derivatives of a JSBSim aircraft (project name, stock JSBSim name or XML path)
    trimmed at ``altitude`` (m above sea level), true airspeed ``speed`` (m/s), flight-path
    angle ``gamma``, ``bank`` and ``flaps`` (rad); ``axes`` 'body' or 'stability'."""
    model = load(aircraft)
    trimmed = trim(model, altitude, speed, gamma, bank, flaps)
    return derivatives(model, trimmed, axes=axes, propulsion=propulsion)


def methods() -> dict[str, Method]:
    """{id: Method} of every registered identification method (built-in and plug-ins)."""
    return registry.methods()


# re-exported: identify(record, method, model, **options) -> Estimate;
# score(estimate, truth) -> Score
_ = (identify, score, Score)
