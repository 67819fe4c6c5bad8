"""Flight cards: one TOML file says what to fly, and ``fly_card`` flies it.

Schema (every length in m, speed in m/s, time in s, rate in Hz; angles in rad, or in
degrees with a ``_deg`` suffix). See ``scenarios/library/example.toml`` for a commented card.

    name = "navion-demo"        # optional, default: the file name
    description = "one line"    # shown by `flightid simulate --list`
    source = "Catterall (2003)" # where the flight test comes from
    aircraft = "navion"         # a project aircraft or one shipped with JSBSim
    duration = 50.0             # s of flight after trim
    rate = 100.0                # Hz of the truth record (JSBSim runs at >= 400 Hz)
    seed = 1                    # default random seed (noise, turbulence, pilot)

    [condition]                 # trimmed start: altitude and speed required
    altitude = 0.0              # m above sea level
    speed = 53.64               # m/s true airspeed
    gamma_deg = 0.0             # flight-path angle; bank_deg, flaps_deg likewise

    [[maneuver]]                # any number; kinds of flightid.scenarios.inputs.INPUT_KINDS
    kind = "3211"               # doublet 21 211 3211 pulse multistep step sweep multisine
    surface = "de"              # orthogonal_multisine pullup_pushover throttle_cut
    start = 5.0                 # bank_to_bank figure_eight (hand-flown, seeded pilot)
    base = 0.5
    amplitude_deg = 2.0

    [sensors]                   # optional; without it the measured record is the truth
    suite = "research"          # built-in suite (hobby, research, ideal) to start from
    output_rate = 50.0          # other keys as flightid.sim.sensors.tables.suite_from_dict
    drop = ["rpm"]              # channels or mounting effects to remove from the suite
    mounting = [{effect = "lever_arm", x = 0.3}]  # lever_arm, vanes, engine_vibration
    [sensors.channels]          # per-channel overrides replace that channel's chain
    q = [{effect = "sample", rate = 50.0}, {effect = "noise", sigma_deg = 0.1}]

    [[disturbance]]             # wind, gust, turbulence, engine_vibration
    kind = "turbulence"
    intensity = "light"

    [[effect]]                  # airframe and actuator effects: flown in an augmented
    name = "rate_limit"         # copy of the aircraft's JSBSim XML (flightid.sim.augment)
    surface = "de"
    rate_deg = 20.0

Every ``effect`` and ``kind`` above names one entry of the effect catalogue
(``flightid.sim.effects.catalogue.CATALOGUE``; ``flightid effects`` lists it, with each
effect's parameters, units and defaults; docs/effects.md): sensor effects in a channel's
chain, mounting and vibration effects in ``mounting``, disturbances and vibration in
``[[disturbance]]``, airframe and actuator effects in ``[[effect]]`` (``name = ...``).
An unknown name, or one given in the wrong place, is an error that
names the file, line and field and lists the names valid there. ``Card.effects`` maps
each such field to its catalogue entry.

``load_card(path) -> Card`` validates everything and raises ``CardError`` naming the file,
the line and the field. ``fly_card(card, seed) -> (measured, truth)`` is a pure function
of its arguments: same card and seed, identical records; another seed changes only the
random parts (sensor noise, turbulence, the hand-flying pilot). Each random part draws
from its own stream derived from the seed, so adding one leaves the others unchanged.
A card with ``[[effect]]`` tables flies the aircraft augmented with them (written once per
aircraft and effect list into a cache folder, ``AUGMENT_CACHE``); the truth record's
``meta.extra["injected"]`` lists every injected effect with its magnitude.

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
