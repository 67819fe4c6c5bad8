"""The public API of flightid, re-exported by the ``flightid`` package:

- ``fly(card, seed)`` -> ``Flight``: fly a flight card in JSBSim;
- ``truth(aircraft, altitude, speed, ...)``: the exact derivatives of a JSBSim aircraft;
- ``identify(record, method, model, **options)`` -> ``Estimate``; ``methods()``: the
  registered methods;
- ``score(estimate, truth)`` -> ``Score``;
- ``gap(...)``: the model-gap diagnosis of a record; ``gap_benchmark(...)``: its blind check;
- ``montecarlo(...)``: a Monte Carlo study; ``design_compare(...)``: input designs compared;
- ``FlightRecord`` and ``read(path)``: the flight record and its reader;
- ``EXCITATION_ENV``: the id of the gymnasium excitation environment.

    import flightid
    flight = flightid.fly("navion-demo", seed=1)
    est = flightid.identify(flight.measured, method="oe", model="lon")
    print(flightid.score(est, flight.truth).verdict)

Every command of the command line is a thin call of these functions. ``gap``,
``gap_benchmark``, ``montecarlo`` and ``design_compare`` (Dask, matplotlib) are loaded on
first use (PEP 562).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import import_module
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.scoring import Score, record_truth, score
from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.identification.methods.protocol import Method
from flightid.record import FlightRecord, read
from flightid.scenarios.cards import Card, fly_card, load_card
from flightid.scenarios.gym.registration import ENV_ID as EXCITATION_ENV
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.sim.jsbsim.truth import Truth, derivatives

if TYPE_CHECKING:  # loaded on first use by __getattr__ below
    from flightid.identification.gap import diagnose as gap
    from flightid.scenarios.gap_benchmark import benchmark as gap_benchmark
    from flightid.scenarios.montecarlo import run as montecarlo
    from flightid.scenarios.montecarlo.design.report import compare_and_report as design_compare

__all__ = ["EXCITATION_ENV", "Estimate", "Flight", "FlightRecord", "Score", "design_compare",
           "fly", "gap", "gap_benchmark", "identify", "methods", "montecarlo", "read", "score",
           "truth"]
# loaded on first use: {name: (package, attribute)}, as ``from package import attribute``
_LAZY = {
    "gap": ("flightid.identification.gap", "diagnose"),
    "gap_benchmark": ("flightid.scenarios.gap_benchmark", "benchmark"),
    "montecarlo": ("flightid.scenarios.montecarlo", "run"),
    "design_compare": ("flightid.scenarios.montecarlo.design.report", "compare_and_report"),
}


def __getattr__(name: str) -> Any:
    """``gap``, ``gap_benchmark``, ``montecarlo``, ``design_compare``, imported on first use."""
    if name not in _LAZY:
        raise AttributeError(f"module 'flightid.api' has no attribute {name!r}")
    package, attribute = _LAZY[name]
    value = getattr(import_module(package), attribute)
    globals()[name] = value
    return value


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
    """Fly a flight card in JSBSim; a pure function of card and seed.

    Parameters
    ----------
    card : str, Path or Card
        A library name such as "navion-demo", a TOML path, or a Card.
    seed : int, optional
        The seed of sensor noise and turbulence (default: the card's).

    Returns
    -------
    Flight
        The measured and the true record (SI units, angles in rad), the exact derivatives
        (per rad) and the card's maneuvers and a priori values.
    """
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
    """Exact derivatives of a JSBSim aircraft at a trimmed condition.

    Parameters
    ----------
    aircraft : str
        A project name, a stock JSBSim name or an XML path.
    altitude : float
        Altitude above sea level, m.
    speed : float
        True airspeed, m/s.
    gamma, bank, flaps : float
        Flight-path angle, bank angle and flap deflection, rad.
    axes : str
        'body' or 'stability'.
    propulsion : bool
        Include the propeller's contribution.

    Returns
    -------
    Truth
        The trim and the derivatives (per rad, rates nondimensional).
    """
    model = load(aircraft)
    trimmed = trim(model, altitude, speed, gamma, bank, flaps)
    return derivatives(model, trimmed, axes=axes, propulsion=propulsion)


def methods() -> dict[str, Method]:
    """Every registered identification method, built-in and plug-ins.

    Returns
    -------
    dict of str to Method
        {id: Method}.
    """
    return registry.methods()
