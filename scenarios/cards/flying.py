"""Flying a card: ``fly_card(card, seed) -> (measured, truth)``, a pure function of the card
and the seed, each random part drawing from its own stream derived from the seed."""

from __future__ import annotations

import dataclasses
import tempfile
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from flightid.record import FlightRecord
from flightid.scenarios.cards.schema import Card
from flightid.scenarios.flight_meta import maneuver_list, truth_table
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import total_signals
from flightid.sim.augment import augment_cached
from flightid.sim.effects.vibration import EngineVibration
from flightid.sim.flight.disturbed import (
    atmosphere_for,
    fly_disturbed,
    vibration_of,
    wind_schedule,
)
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.sensors.suites import measure

# where fly_card writes augmented aircraft (one folder per aircraft and effect list)
AUGMENT_CACHE = Path(tempfile.gettempdir()) / "flightid-augmented"


def sub_seed(seed: int, purpose: str) -> int:
    """An independent 32-bit seed for one random part of a flight (e.g. 'sensors').

    Parameters
    ----------
    seed : int
        The flight's seed.
    purpose : str
        Name of the random part.

    Returns
    -------
    int
        Seed in 0..2**32 - 1.
    """
    ss = np.random.SeedSequence([int(seed), zlib.crc32(purpose.encode())])
    return int(ss.generate_state(1)[0])


def _flown_designs(card: Card, seed: int) -> list[InputDesign]:
    """The card's maneuvers with each hand-flying pilot reseeded from the flight's seed."""
    out = []
    for i, d in enumerate(card.maneuvers):
        if any(f.name == "seed" for f in dataclasses.fields(d)):
            d = dataclasses.replace(d, seed=sub_seed(seed, f"pilot:{i}:{d.seed}"))
        out.append(d)
    return out


def trim_card(card: Card):
    """The card's aircraft (augmented when the card says so) and its trim at the card's
    condition: ``(model, trimmed)``. Raises TrimError (a condition that cannot be flown)
    or TrimInputError (one that is not a condition).

    Parameters
    ----------
    card : Card
        The flight card.

    Returns
    -------
    tuple
        (model, trimmed): the loaded JSBSim model and its trim.
    """
    model = load(augmented(card) if card.augmentation else card.aircraft)
    return model, trim(model, card.condition)


def fly_card(card: Card, seed: int | None = None,
             progress: Callable[[int, int], None] | None = None
             ) -> tuple[FlightRecord, FlightRecord]:
    """Fly a card: (measured, truth) records; a pure function of the card and the seed.

    The truth is sampled at the card's rate; the measured record is the truth through
    the card's sensor suite (the truth itself without one). Both carry the card
    (``meta.scenario['card']``) and the seed (``meta.scenario['seed']``). Raises
    TrimError or DepartureError (with ``.record``) from the flight core.

    Parameters
    ----------
    card : Card
        The flight card.
    seed : int or None, optional
        Seed, 0..2**32 - 1; None uses the card's seed.
    progress : callable or None, optional
        ``progress(k, n)`` with k samples of n flown.

    Returns
    -------
    tuple[FlightRecord, FlightRecord]
        (measured, truth) records.
    """
    seed = card.seed if seed is None else int(seed)
    if not 0 <= seed <= 2**32 - 1:
        raise ValueError(f"seed must be 0..{2**32 - 1} (a 32-bit random seed), got {seed}")
    model, trimmed = trim_card(card)
    n = int(round(card.duration * card.rate)) + 1
    t = np.arange(n) / card.rate
    designs = _flown_designs(card, seed)
    controls = total_signals(designs, t) if designs else {}
    rng = np.random.default_rng(sub_seed(seed, "turbulence"))
    gusts, turb = wind_schedule(card.disturbances, n, card.rate, trimmed, rng)
    scenario = {"card": card.to_dict(), "seed": seed, "name": card.name}
    try:
        truth = fly_disturbed(model, trimmed, controls, card.duration, card.rate,
                              atmosphere_for(card.disturbances, sub_seed(seed, "jsbsim")),
                              wind=gusts, turbulence=turb, scenario=scenario,
                              progress=progress)
    except DepartureError as exc:
        raise DepartureError(f"{exc.reason} (card {card.name}, seed {seed})", exc.time,
                             exc.record) from None
    truth.meta.extra["inputs"] = [d.to_dict() for d in designs]
    truth.meta.extra["disturbances"] = [d.to_dict() for d in card.disturbances]
    if card.augmentation:
        # what was injected, for scoring a diagnosis; a diagnosis must not read it
        truth.meta.extra["injected"] = {"aircraft": card.aircraft,
                                        "augmented": model.name,
                                        "effects": [e.to_dict() for e in card.augmentation]}
    truth.meta.extra["maneuvers"] = maneuver_list(designs)
    truth.meta.extra["truth"] = truth_table(model, trimmed)
    if card.a_priori:
        truth.meta.extra["a_priori"] = {k: dict(v) for k, v in card.a_priori.items()}
    if card.sensors is None:
        return truth, truth
    suite = card.sensors
    vib = vibration_of(card.disturbances)
    if vib is not None:
        suite = dataclasses.replace(suite, mounting=[
            m for m in suite.mounting if not isinstance(m, EngineVibration)] + [vib])
    return measure(truth, suite, sub_seed(seed, "sensors")), truth


def augmented(card: Card, cache: Path | None = None) -> str:
    """The XML path of the card's aircraft with its [[effect]]s (written once, then reused).

    Parameters
    ----------
    card : Card
        The flight card.
    cache : Path or None, optional
        Cache folder; None uses the default.

    Returns
    -------
    str
        Path of the augmented aircraft's XML.
    """
    return augmented_aircraft(card.aircraft, card.augmentation, cache)


def augmented_aircraft(aircraft: str, effects: Sequence[Any], cache: Path | None = None) -> str:
    """The XML path of ``aircraft`` with the airframe and actuator ``effects`` (catalogue
    effects), written once into the cache folder, then reused.

    Parameters
    ----------
    aircraft : str
        Aircraft name.
    effects : Sequence[Any]
        Catalogue effects.
    cache : Path or None, optional
        Cache folder; None uses the default.

    Returns
    -------
    str
        Path of the augmented aircraft's XML.
    """
    return str(augment_cached(aircraft, tuple(effects), cache or AUGMENT_CACHE,
                              name=f"{aircraft}-augmented"))
