"""``design-optimize``: a multisine optimised for the predicted bounds of a card's
derivatives, against the built-in designs flown one surface after another as the cards
do (``input_information`` for the prediction, ``input_optimization`` for the optimiser).

The problem is measured on the card itself: a flight without inputs (the card's
condition, sensors and turbulence, seed of the card) gives the trim condition, the JSBSim
truth and the residual spectrum. Every built-in design is applied to each surface in
turn (the next ``design.GAP_S`` s after the previous input ends), all scaled to the energy of
the ``reference`` built-in; the multisine gets that energy and the reference's input
time, so it flies as long as the reference does. With ``equal_duration`` every built-in
is also stretched or compressed in time (its base, sweep duration or multisine period) to
the reference's input time, so that all designs carry the same energy over the same
duration.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.channels import LATERAL_INPUTS
from flightid.scenarios.cards import card_from_dict, fly_card, load_card
from flightid.scenarios.equal_energy import scale_to_energy
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.input_information import (
    Problem,
    mean_relative_bound,
    predicted_bounds,
    problem_from_flight,
)
from flightid.scenarios.input_optimization import OptimizedMultisine, optimize_multisine
from flightid.scenarios.inputs import Maneuvers
from flightid.scenarios.montecarlo.design.experiment import (
    DESIGNS,
    SETTLE_S,
    START_S,
    DesignSettings,
    card_text,
    design_card,
    input_energy,
    make_design,
    maneuver_dicts,
    peak,
    time_grid,
)
from flightid.scenarios.peak_limit import limit_peak

QUIET_S = 60.0  # s of the flight without inputs that measures the residual spectrum


def sequenced(kind: str, surfaces: Sequence[str], settings: DesignSettings) -> InputDesign:
    """Built-in design ``kind`` on each of ``surfaces`` in turn from START_S (``make_design``
    with ``then``).

    Parameters
    ----------
    kind : str
        Built-in design kind (``DESIGNS``).
    surfaces : Sequence[str]
        Surfaces, in flying order; at least one.
    settings : DesignSettings
        Amplitude (rad) and the other settings.

    Returns
    -------
    InputDesign
        The design (a ``Maneuvers`` for several surfaces).
    """
    return make_design(kind, dataclasses.replace(settings, surface=surfaces[0],
                                                 then=tuple(surfaces[1:])))


def stretched(kind: str, surfaces: Sequence[str], settings: DesignSettings, span: float
              ) -> InputDesign:
    """Built-in design ``kind`` on each of ``surfaces`` in turn (``sequenced``) with its
    time parameter (multi-step base, sweep duration or multisine period, s) scaled so that
    its input time, the first input's start to the last one's end, is ``span`` (s).

    Parameters
    ----------
    kind : str
        Built-in design kind (``DESIGNS``).
    surfaces : Sequence[str]
        Surfaces, in flying order.
    settings : DesignSettings
        Amplitude (rad) and the other settings.
    span : float
        Input time wanted, s.

    Returns
    -------
    InputDesign
        The stretched design.
    """
    own = sequenced(kind, surfaces, settings)
    first = own.parts[0] if isinstance(own, Maneuvers) else own
    length = first.end - first.start
    each = (span - (own.end - own.start - len(surfaces) * length)) / len(surfaces)
    if not each > 0:
        raise ValueError(f"an input time of {span:g} s leaves no time for {kind!r} on "
                         f"{len(surfaces)} surfaces")
    c = each / length
    return sequenced(kind, surfaces, dataclasses.replace(
        settings, base=settings.base * c, sweep_duration=settings.sweep_duration * c,
        multisine_period=settings.multisine_period * c))


def card_problem(card: str, model: str = "lat", derivatives: Sequence[str] | None = None
                 ) -> Problem:
    """The design problem of ``card``: a QUIET_S s flight of it without inputs.

    Parameters
    ----------
    card : str
        Library card name or card file.
    model : str, optional
        Linear model preset. Default ``"lat"``.
    derivatives : Sequence[str] or None, optional
        Derivatives whose bounds count; None uses the model's.

    Returns
    -------
    Problem
        The design problem.
    """
    base = load_card(card)
    data = {k: v for k, v in base.data.items() if k != "maneuver"}
    data["duration"] = QUIET_S
    measured, truth = fly_card(card_from_dict(data, base.path), base.seed)
    return problem_from_flight(measured, truth, model, derivatives)


@dataclass
class Optimized:
    """The optimised multisine and every design's predicted bounds (the derivatives'
    units), mean bound / |truth|, energy (rad^2 s), input and flight time (s), peak (rad)."""

    problem: Problem
    multisine: OptimizedMultisine
    designs: dict[str, InputDesign]
    predicted: dict[str, dict[str, float]] = field(default_factory=dict)
    rows: list[dict[str, Any]] = field(default_factory=list)

    def best_builtin(self) -> str:
        """The built-in design with the smallest predicted mean bound / |truth|."""
        return min((r for r in self.rows if r["design"] != "optimized"),
                   key=lambda r: r["mean_relative_bound"])["design"]

    def gain(self) -> float:
        """1 - optimised / best built-in mean bound / |truth| (a fraction)."""
        by = {r["design"]: r["mean_relative_bound"] for r in self.rows}
        return 1.0 - by["optimized"] / by[self.best_builtin()]

    def maneuver_table(self, name: str = "optimized") -> str:
        """The optimised design as a maneuver table (TOML, read by ``--design-file``)."""
        return card_text({"name": name, "description":
                          f"design-optimize: {self.multisine.criterion}-optimal multisine "
                          f"on {', '.join(self.multisine.components)}",
                          "maneuver": maneuver_dicts(self.designs["optimized"])})


def optimize(card: str = "navion-demo", model: str = "lat",
             surfaces: Sequence[str] = LATERAL_INPUTS, criterion: str = "A",
             band: tuple[float, float] = (0.1, 2.0), reference: str = "3211",
             settings: DesignSettings | None = None,
             derivatives: Sequence[str] | None = None,
             problem: Problem | None = None, equal_duration: bool = False,
             max_amplitude: float | None = None) -> Optimized:
    """Optimise a multisine on ``surfaces`` for ``criterion`` at the energy and input time
    of the built-in ``reference`` flown on each surface in turn at the settings'
    amplitude (default 4 deg, as the library cards' lateral inputs); predict every
    built-in's bounds at that energy too, each at its own input time or, with
    ``equal_duration``, at the reference's (``stretched``). With ``max_amplitude`` (rad)
    the multisine's peak on every surface is held at or below it (``limit_peak``; raises
    ``PeakLimitError`` if no design found at that energy fits).

    Parameters
    ----------
    card : str, optional
        Library card name or card file. Default ``"navion-demo"``.
    model : str, optional
        Linear model preset. Default ``"lat"``.
    surfaces : Sequence[str], optional
        Surfaces the inputs move. Default the lateral ones.
    criterion : str, optional
        ``"A"`` (default), ``"D"`` or ``"mean"``.
    band : tuple[float, float], optional
        Multisine frequency band, Hz. Default (0.1, 2.0).
    reference : str, optional
        Built-in design that sets the energy and input time. Default ``"3211"``.
    settings : DesignSettings or None, optional
        Amplitude (rad) and the other settings; None uses 4 deg.
    derivatives : Sequence[str] or None, optional
        Derivatives whose bounds count; None uses the model's.
    problem : Problem or None, optional
        The design problem; None flies ``card`` without inputs (:func:`card_problem`).
    equal_duration : bool, optional
        Stretch every built-in to the reference's input time. Default False.
    max_amplitude : float or None, optional
        Limit of the multisine's peak deflection on every surface (rad); None: none.

    Returns
    -------
    Optimized
        The optimised multisine and every design's predicted bounds.
    """
    settings = settings or DesignSettings(amplitude=np.deg2rad(4.0))
    if reference not in DESIGNS:
        raise ValueError(f"unknown reference design {reference!r}; designs: "
                         f"{', '.join(DESIGNS)}")
    pb = problem or card_problem(card, model, derivatives)
    rate = pb.rate
    ref = sequenced(reference, surfaces, settings)
    energy = input_energy(ref, rate)
    designs: dict[str, InputDesign] = {}
    span = ref.end - ref.start
    for kind in DESIGNS:
        d = (stretched(kind, surfaces, settings, span) if equal_duration
             else sequenced(kind, surfaces, settings))
        designs[kind] = scale_to_energy(d, time_grid(d, rate), energy)
    ms = optimize_multisine(pb, tuple(surfaces), band, span, energy, criterion,
                            start=START_S, settle=SETTLE_S)
    if max_amplitude is not None:
        ms = limit_peak(pb, ms, energy, max_amplitude, START_S + span + SETTLE_S)
    designs["optimized"] = ms.design()
    out = Optimized(pb, ms, designs)
    for name, d in designs.items():
        b = predicted_bounds(pb, d, d.end + SETTLE_S)
        out.predicted[name] = b
        out.rows.append({"design": name, "mean_relative_bound": mean_relative_bound(pb, b),
                         "energy": input_energy(d, rate), "input_time": d.end - d.start,
                         "flight_time": float(time_grid(d, rate)[-1]),
                         "peak": peak(d, rate)})
    return out


@dataclass(frozen=True)
class Envelope:
    """Limits of a flight: largest |bank| (rad), largest alpha (rad), largest relative
    airspeed change |V - V0| / V0 (fraction)."""

    bank: float = np.deg2rad(30.0)
    alpha: float = np.deg2rad(15.0)
    speed: float = 0.10


def envelope_excursions(card: str, design: InputDesign) -> dict[str, float]:
    """Fly ``design`` on ``card`` (its condition, turbulence and seed) in JSBSim for the
    input and SETTLE_S s after: the largest |bank| and alpha (rad) and relative airspeed
    change (fraction) of the true flight. Raises DepartureError if it departs.

    Parameters
    ----------
    card : str
        Library card name or card file.
    design : InputDesign
        The design flown.

    Returns
    -------
    dict[str, float]
        ``"bank"`` and ``"alpha"``, rad; ``"speed"``, fraction.
    """
    base = load_card(card)
    data = design_card(base.to_dict(), "optimized", design, base.rate)
    _, truth = fly_card(card_from_dict(data, base.path), base.seed)
    v0 = float(truth["V"][0])
    return {"bank": float(np.max(np.abs(truth["phi"]))),
            "alpha": float(np.max(truth["alpha"])),
            "speed": float(np.max(np.abs(truth["V"] - v0)) / v0)}


def envelope_violations(excursions: dict[str, float], limits: Envelope) -> list[str]:
    """The limits an excursion exceeds, each as a sentence naming it.

    Parameters
    ----------
    excursions : dict[str, float]
        As returned by :func:`envelope_excursions`.
    limits : Envelope
        The limits.

    Returns
    -------
    list[str]
        One sentence per exceeded limit; empty if none.
    """
    out = []
    if excursions["bank"] > limits.bank:
        out.append(f"bank {np.rad2deg(excursions['bank']):.1f} deg exceeds "
                   f"{np.rad2deg(limits.bank):.1f} deg")
    if excursions["alpha"] > limits.alpha:
        out.append(f"alpha {np.rad2deg(excursions['alpha']):.1f} deg exceeds "
                   f"{np.rad2deg(limits.alpha):.1f} deg")
    if excursions["speed"] > limits.speed:
        out.append(f"airspeed change {100 * excursions['speed']:.1f} % exceeds "
                   f"{100 * limits.speed:.1f} %")
    return out
