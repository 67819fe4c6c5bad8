"""Flight cards: one TOML file says what to fly, and ``fly_card`` flies it.

A card gives the aircraft and its trimmed condition, the maneuvers, the sensor suite, the
disturbances, airframe and actuator effects, the seed and the duration (lengths m, speeds
m/s, times s, rates Hz, angles rad or degrees with a ``_deg`` suffix). The fields are in
docs/cards.md; ``scenarios/library/example.toml`` is a commented card.

``load_card(path) -> Card`` validates everything and raises ``CardError`` naming the file,
the line and the field. ``fly_card(card, seed) -> (measured, truth)`` is a pure function
of its arguments: same card and seed, identical records; another seed changes only the
random parts (sensor noise, turbulence, the hand-flying pilot).

Modules: ``schema`` (``Card``, ``CardError``, the fields), ``library`` (locating cards),
``parse`` (``load_card``, ``card_from_dict``, ``load_maneuvers``), ``overrides`` (the
command line's ``--set``, ``--turbulence``, ``--sensors``), ``flying`` (``fly_card``).
"""

from flightid.scenarios.cards.flying import (
    AUGMENT_CACHE,
    augmented,
    augmented_aircraft,
    fly_card,
    sub_seed,
    trim_card,
)
from flightid.scenarios.cards.library import describe, find_card, library_cards
from flightid.scenarios.cards.overrides import TURBULENCE_LEVELS, overridden_card, override
from flightid.scenarios.cards.parse import card_from_dict, load_card, load_maneuvers
from flightid.scenarios.cards.schema import Card, CardError, Condition, FlightCondition

__all__ = ["AUGMENT_CACHE", "TURBULENCE_LEVELS", "Card", "CardError", "Condition",
           "FlightCondition", "augmented", "augmented_aircraft", "card_from_dict", "describe",
           "find_card", "fly_card", "library_cards", "load_card", "load_maneuvers", "override",
           "overridden_card", "sub_seed", "trim_card"]
