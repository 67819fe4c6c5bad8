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
"""

from __future__ import annotations

import dataclasses
import math
import re
import tempfile
import tomllib
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flightid.derivatives import is_derivative
from flightid.record import FlightRecord
from flightid.scenarios.flight_meta import maneuver_list, truth_table
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import input_from_dict, total_signals
from flightid.scenarios.toml_locate import line_index, line_of
from flightid.sim.augment import augment_cached
from flightid.sim.effects.catalogue import CATALOGUE, SECTIONS
from flightid.sim.effects.vibration import EngineVibration
from flightid.sim.flight.disturbed import (
    Gust,
    atmosphere_for,
    disturbance_from_dict,
    fly_disturbed,
    vibration_of,
    wind_schedule,
)
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.sim.jsbsim.model import available, load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.sensors.builtin import SUITES
from flightid.sim.sensors.suites import measure
from flightid.sim.sensors.tables import suite_from_dict
from flightid.units import DEG

LIBRARY = Path(__file__).resolve().parent / "library"
TOP_FIELDS = ("name", "description", "source", "aircraft", "duration", "rate", "seed",
              "condition", "maneuver", "sensors", "disturbance", "effect", "a_priori")
# where fly_card writes augmented aircraft (one folder per aircraft and effect list)
AUGMENT_CACHE = Path(tempfile.gettempdir()) / "flightid-augmented"
A_PRIORI_FIELDS = ("value", "std", "source")
CONDITION_FIELDS = ("altitude", "speed", "gamma", "bank", "flaps")
NO_SENSORS = "none"


class CardError(ValueError):
    """A mistake in a flight card: ``path``, ``line`` (1-based or None) and ``field``."""

    def __init__(self, path: str, line: int | None, field: str | None, message: str) -> None:
        where = f"{path}:{line}" if line else str(path)
        what = f"field '{field}': " if field and f"'{field}'" not in message else ""
        super().__init__(f"{where}: {what}{message}")
        self.path = str(path)
        self.line = line
        self.field = field
        self.message = message


# a card's [condition] table (altitude, speed, gamma, bank, flaps in card units) is read
# into the one flight-condition type of flightid.sim.jsbsim.condition
Condition = FlightCondition


@dataclass
class Card:
    """A validated flight card; ``data`` is the card as parsed (plain dict, card units)."""

    name: str
    aircraft: str
    condition: FlightCondition
    duration: float
    rate: float
    seed: int
    maneuvers: tuple[InputDesign, ...] = ()
    sensors: Any = None  # flightid.sim.sensors.suites.SensorSuite or None
    disturbances: tuple[Any, ...] = ()
    # airframe and actuator effects ([[effect]]), flown in an augmented aircraft
    augmentation: tuple[Any, ...] = ()
    description: str = ""
    source: str = ""
    path: str = ""
    data: dict[str, Any] = field(default_factory=dict)
    # parameters an identification holds fixed: {name: {"value", "std", "source"}}
    a_priori: dict[str, dict[str, Any]] = field(default_factory=dict)
    # each card field that injects an effect -> its catalogue entry, e.g.
    # {"sensors.channels.q[1]": "noise", "disturbance[0]": "turbulence"}
    effects: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The card as written (a JSON-able dict), for record metadata."""
        return _plain(self.data)


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    return x


# -- locating cards -----------------------------------------------------------------------


def library_cards() -> dict[str, Path]:
    """Library card names -> paths (scenarios/library/*.toml)."""
    return {p.stem: p for p in sorted(LIBRARY.glob("*.toml"))}


def find_card(name_or_path: str | Path) -> Path:
    """Path of a card given as a file path or a library card name."""
    p = Path(name_or_path)
    if p.is_file():
        return p
    lib = library_cards()
    stem = p.stem if p.suffix == ".toml" else p.name
    if str(name_or_path) == stem and stem in lib:
        return lib[stem]
    raise CardError(str(name_or_path), None, None,
                    f"no such card file, and not a library card; library cards: "
                    f"{', '.join(lib) or 'none'}")


def describe(path: Path) -> str:
    """The one-line description of a card file (without validating it)."""
    try:
        return str(tomllib.loads(path.read_text(encoding="utf-8")).get("description", ""))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        return f"(unreadable: {exc})"


# -- parsing --------------------------------------------------------------------------------


_FIELD = re.compile(r"field '([^']+)'")
_LEAD = re.compile(r"^([A-Za-z_][\w.\[\]]*): ")


def _path_of(field_name: str) -> tuple:
    """'maneuver[2].amplitude_deg' -> ('maneuver', 2, 'amplitude_deg')."""
    out: list = []
    for part in field_name.split("."):
        m = re.fullmatch(r"([^\[\]]+)((?:\[\d+\])*)", part)
        if not m:
            out.append(part)
            continue
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(out)


class _Checker:
    """Raises CardError with file, line and field for a card being parsed."""

    def __init__(self, path: str, text: str | None) -> None:
        self.path = path
        self.index = line_index(text) if text else {}

    def fail(self, field_name: str, message: str) -> CardError:
        line = line_of(self.index, _path_of(field_name)) if self.index else None
        return CardError(self.path, line, field_name, message)

    def wrap(self, exc: Exception, context: str) -> CardError:
        """A CardError from a builder's ValueError, locating the field it names."""
        msg = str(exc)
        m = _FIELD.search(msg) or _LEAD.search(msg)
        name = m.group(1) if m else context
        if not (name == context or name.startswith(context + ".")
                or name.startswith(context + "[")):
            name = f"{context}.{name}"
        return self.fail(name, msg)

    def number(self, d: dict, key: str, where: str, default: float | None = None,
               positive: bool = False) -> float:
        if key not in d:
            if default is None:
                raise self.fail(where, "is required")
            return default
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(where, f"must be a number, got {v!r}")
        if positive and not v > 0:
            raise self.fail(where, f"must be > 0, got {v!r}")
        return float(v)


def _angle(chk: _Checker, d: dict, name: str, where: str) -> float:
    if name in d and f"{name}_deg" in d:
        raise chk.fail(f"{where}.{name}_deg", f"given twice (as {name!r} and {name}_deg)")
    if f"{name}_deg" in d:
        return chk.number(d, f"{name}_deg", f"{where}.{name}_deg") * DEG
    return chk.number(d, name, f"{where}.{name}", default=0.0)


def _condition(chk: _Checker, d: Any) -> FlightCondition:
    if not isinstance(d, dict):
        raise chk.fail("condition", "must be a table ([condition])")
    for key in d:
        base = key[:-4] if key.endswith("_deg") else key
        if base not in CONDITION_FIELDS or (key.endswith("_deg") and base in ("altitude",
                                                                              "speed")):
            raise chk.fail(f"condition.{key}", "unknown field; allowed: altitude, speed, "
                           "gamma(_deg), bank(_deg), flaps(_deg)")
    altitude = chk.number(d, "altitude", "condition.altitude")
    speed = chk.number(d, "speed", "condition.speed", positive=True)
    if altitude < 0:
        raise chk.fail("condition.altitude", f"must be >= 0 m, got {altitude}")
    return FlightCondition(altitude, speed, _angle(chk, d, "gamma", "condition"),
                     _angle(chk, d, "bank", "condition"), _angle(chk, d, "flaps", "condition"))


def _maneuvers(chk: _Checker, items: Any, duration: float) -> tuple[InputDesign, ...]:
    if not isinstance(items, list):
        raise chk.fail("maneuver", "must be an array of tables ([[maneuver]])")
    out = []
    for i, d in enumerate(items):
        where = f"maneuver[{i}]"
        if not isinstance(d, dict):
            raise chk.fail(where, f"must be a table, got {d!r}")
        try:
            design = input_from_dict(d, where)
        except ValueError as exc:
            raise chk.wrap(exc, where) from None
        if design.start < 0:
            raise chk.fail(f"{where}.start", f"starts at {design.start:g} s, before the flight")
        if design.start >= duration:
            raise chk.fail(f"{where}.start", f"starts at {design.start:g} s, after the flight "
                           f"ends ({duration:g} s)")
        if design.end > duration + 1e-9:
            raise chk.fail(f"{where}.start" if "start" in d else where,
                           f"the {design.kind} runs from {design.start:g} to "
                           f"{design.end:g} s, beyond the flight's duration {duration:g} s")
        out.append(design)
    return tuple(out)


def _sensors(chk: _Checker, d: Any) -> Any:
    if d == NO_SENSORS:
        return None
    if isinstance(d, str):
        d = {"suite": d}
    if not isinstance(d, dict):
        raise chk.fail("sensors", f"must be a table or a suite name, got {d!r}")
    if d.get("suite") == NO_SENSORS:
        if len(d) > 1:
            raise chk.fail("sensors.suite", "suite 'none' takes no other sensor fields")
        return None
    body = {("base" if k == "suite" else k): v for k, v in d.items() if k != "drop"}
    if "base" in body and not isinstance(body["base"], str):
        raise chk.fail("sensors.suite", f"must be a suite name, got {body['base']!r}")
    try:
        suite = suite_from_dict(body)
    except ValueError as exc:
        # the suite's fields are the card's sensors.<field> (its base is sensors.suite)
        msg = str(exc).replace("field 'base'", "field 'suite'")
        msg = re.sub(r"field '(?!sensors\.)", "field 'sensors.", msg)
        raise chk.wrap(ValueError(msg), "sensors") from None
    drop = d.get("drop", [])
    if not isinstance(drop, list) or not all(isinstance(x, str) for x in drop):
        raise chk.fail("sensors.drop", f"must be a list of channel or mounting-effect names, "
                       f"got {drop!r}")
    mounting = {m.name for m in suite.mounting}
    for i, name in enumerate(drop):
        if name not in suite.channels and name not in mounting:
            raise chk.fail(f"sensors.drop[{i}]", f"{name!r} is neither a channel nor a "
                           f"mounting effect of the suite; it has {', '.join(suite.channels)}; "
                           f"{', '.join(mounting) or 'no mounting effects'}")
    return dataclasses.replace(
        suite, channels={c: e for c, e in suite.channels.items() if c not in drop},
        mounting=[m for m in suite.mounting if m.name not in drop])


def _disturbances(chk: _Checker, items: Any, duration: float) -> tuple[Any, ...]:
    if not isinstance(items, list):
        raise chk.fail("disturbance", "must be an array of tables ([[disturbance]])")
    out = []
    for i, d in enumerate(items):
        where = f"disturbance[{i}]"
        try:
            dist = disturbance_from_dict(d, where)
        except ValueError as exc:
            raise chk.wrap(exc, where) from None
        if isinstance(dist, Gust) and dist.start >= duration:
            raise chk.fail(f"{where}.start", f"gust at {dist.start:g} s is after the flight "
                           f"ends ({duration:g} s)")
        out.append(dist)
    try:
        vibration_of(out)
    except ValueError as exc:
        raise chk.fail("disturbance", str(exc)) from None
    return tuple(out)


def _augmentation(chk: _Checker, items: Any) -> tuple[Any, ...]:
    """[[effect]] tables: airframe and actuator effects of the catalogue, by ``name``."""
    if not isinstance(items, list):
        raise chk.fail("effect", "must be an array of tables ([[effect]])")
    out = []
    for i, d in enumerate(items):
        where = f"effect[{i}]"
        try:
            out.append(CATALOGUE.from_dict(d, "effect", where))
        except ValueError as exc:
            raise chk.wrap(exc, where) from None
    seen: dict[tuple, int] = {}
    for i, e in enumerate(out):
        if e.name in ("derivative_delta", "control_effectiveness"):
            continue
        key = (e.name, e.options().get("surface", ""))
        if key in seen:
            raise chk.fail(f"effect[{i}].name", f"{e.name} given twice (also effect"
                           f"[{seen[key]}]); give it once" + (" per surface" if key[1] else ""))
        seen[key] = i
    return tuple(out)


def _effect_entries(data: dict[str, Any]) -> dict[str, str]:
    """Card field -> catalogue entry of every effect table of a validated card."""
    out: dict[str, str] = {}
    sensors = data.get("sensors")
    tables: list[tuple[str, str, Any]] = []
    if isinstance(sensors, dict):
        for ch, chain in (sensors.get("channels") or {}).items():
            tables += [("channel", f"sensors.channels.{ch}[{i}]", e) for i, e in enumerate(chain)]
        tables += [("mounting", f"sensors.mounting[{i}]", m)
                   for i, m in enumerate(sensors.get("mounting", []))]
    tables += [("disturbance", f"disturbance[{i}]", d)
               for i, d in enumerate(data.get("disturbance", []))]
    tables += [("effect", f"effect[{i}]", d) for i, d in enumerate(data.get("effect", []))]
    for section, where, table in tables:
        out[where] = CATALOGUE.lookup(table[SECTIONS[section].key], section, where).name
    return out


def _a_priori(chk: _Checker, table: Any) -> dict[str, dict[str, Any]]:
    """[a_priori.<derivative>] tables: value (per rad), std (>= 0), source (required)."""
    if not isinstance(table, dict):
        raise chk.fail("a_priori", "must be a table of [a_priori.<derivative>] tables")
    out = {}
    for name, entry in table.items():
        where = f"a_priori.{name}"
        if not is_derivative(name):
            raise chk.fail(where, f"{name!r} is not a derivative name (e.g. Cm_alphadot)")
        if not isinstance(entry, dict):
            raise chk.fail(where, "must be a table with value, std and source")
        for key in entry:
            if key not in A_PRIORI_FIELDS:
                raise chk.fail(f"{where}.{key}", f"unknown field; allowed: "
                               f"{', '.join(A_PRIORI_FIELDS)}")
        value = chk.number(entry, "value", f"{where}.value")
        std = chk.number(entry, "std", f"{where}.std", default=0.0)
        if std < 0:
            raise chk.fail(f"{where}.std", f"must be >= 0, got {std!r}")
        source = entry.get("source")
        if not isinstance(source, str) or not source.strip():
            raise chk.fail(f"{where}.source", "is required: where the value comes from")
        out[name] = {"value": value, "std": std, "source": source}
    return out


def card_from_dict(data: dict[str, Any], path: str = "<card>", text: str | None = None) -> Card:
    """Validate a parsed card; ``text`` (the TOML source) lets errors name the line."""
    chk = _Checker(path, text)
    for key in data:
        if key not in TOP_FIELDS:
            raise chk.fail(key, f"unknown field; allowed: {', '.join(TOP_FIELDS)}")
    for key in ("name", "description", "source"):
        if key in data and not isinstance(data[key], str):
            raise chk.fail(key, f"must be a string, got {data[key]!r}")
    if "aircraft" not in data:
        raise chk.fail("aircraft", "is required")
    aircraft = data["aircraft"]
    if not isinstance(aircraft, str):
        raise chk.fail("aircraft", f"must be a string, got {aircraft!r}")
    known = available()
    if aircraft not in known["project"] and aircraft not in known["jsbsim"]:
        raise chk.fail("aircraft", f"unknown aircraft {aircraft!r}; project aircraft: "
                       f"{', '.join(known['project'])} (or any aircraft shipped with JSBSim)")
    duration = chk.number(data, "duration", "duration", positive=True)
    rate = chk.number(data, "rate", "rate", default=100.0, positive=True)
    seed = data.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise chk.fail("seed", f"must be a whole number >= 0, got {seed!r}")
    if "condition" not in data:
        raise chk.fail("condition", "is required ([condition] with altitude and speed)")
    condition = _condition(chk, data["condition"])
    maneuvers = _maneuvers(chk, data.get("maneuver", []), duration)
    sensors = _sensors(chk, data["sensors"]) if "sensors" in data else None
    disturbances = _disturbances(chk, data.get("disturbance", []), duration)
    if vibration_of(disturbances) is not None and sensors is None:
        raise chk.fail("disturbance", "engine_vibration acts on the sensors; give a [sensors] "
                       "table")
    augmentation = _augmentation(chk, data.get("effect", []))
    default_name = Path(path).stem if path != "<card>" else "card"
    return Card(name=data.get("name", default_name), aircraft=aircraft, condition=condition,
                duration=duration, rate=rate, seed=seed, maneuvers=maneuvers,
                sensors=sensors, disturbances=disturbances, augmentation=augmentation,
                description=data.get("description", ""), source=data.get("source", ""),
                path=str(path), data=data, a_priori=_a_priori(chk, data.get("a_priori", {})),
                effects=_effect_entries(data))


# -- overrides from the command line ---------------------------------------------------------

TURBULENCE_LEVELS = ("none", "light", "moderate")
# keys of the tables whose fields the card schema fixes (other tables are checked by
# card_from_dict, whose errors list the fields allowed there)
_SCHEMA_KEYS: dict[tuple, tuple[str, ...]] = {
    (): TOP_FIELDS,
    ("condition",): ("altitude", "speed", "gamma", "gamma_deg", "bank", "bank_deg", "flaps",
                     "flaps_deg"),
    ("sensors",): ("suite", "output_rate", "drop", "mounting", "channels", "passthrough",
                   "name", "description"),
}

_LIST_FIELDS = (("sensors", "drop"), ("sensors", "passthrough"))


def _override_value(text: str) -> Any:
    """A --set value as a TOML scalar or array; a bare word stays a string and a
    comma-separated list of them an array (``vanes,lever_arm``)."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        pass
    if "," in text:
        return [_override_value(part.strip()) for part in text.split(",") if part.strip()]
    return text.strip()


def _set_path(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``value`` at the TOML path ``key`` of ``data`` (tables created as needed)."""
    path = _path_of(key)
    if not path or any(p == "" for p in path):
        raise ValueError(f"--set {key}: not a card field path (e.g. condition.speed)")
    node: Any = data
    for depth, part in enumerate(path):
        here = re.sub(r"\.(\d+)", r"[\1]", ".".join(map(str, path[:depth]))) or "the card"
        last = depth == len(path) - 1
        if isinstance(part, int):
            if not isinstance(node, list):
                raise ValueError(f"--set {key}: {here} is not an array")
            if not 0 <= part < len(node):
                raise ValueError(f"--set {key}: {here} has {len(node)} entries "
                                 f"(indices 0 to {len(node) - 1})")
        else:
            if not isinstance(node, dict):
                raise ValueError(f"--set {key}: {here} is not a table")
            allowed = _SCHEMA_KEYS.get(tuple(path[:depth]))
            if allowed is not None and part not in allowed:
                raise ValueError(f"--set {key}: unknown field {part!r} in {here}; valid keys: "
                                 f"{', '.join(allowed)}")
        if last:
            old = node[part] if (isinstance(part, int) or part in node) else None
            if ((isinstance(old, list) or tuple(path) in _LIST_FIELDS)
                    and not isinstance(value, list)):
                value = [value]  # one name where a list is expected: a list of one
            node[part] = value
            return
        if isinstance(part, str) and part not in node:
            if isinstance(path[depth + 1], int):
                raise ValueError(f"--set {key}: the card has no {part} entries to index")
            node[part] = {}
        node = node[part]


def override(card_data: dict[str, Any], assignments: Sequence[str] = (),
             turbulence: str | None = None, sensors: str | None = None) -> dict[str, Any]:
    """A copy of a parsed card with command-line overrides applied.

    Parameters
    ----------
    card_data : the card as parsed (``Card.data``); not modified.
    assignments : ``KEY=VALUE`` strings, KEY a card field by its TOML path
        (``condition.speed``, ``sensors.drop``, ``maneuver[0].amplitude_deg``), VALUE a
        TOML scalar or array (a bare word is a string, ``a,b`` an array of two). Applied
        after ``turbulence`` and ``sensors``.
    turbulence : ``none`` removes the card's turbulence, ``light`` or ``moderate`` replaces
        it by the Dryden turbulence of that intensity (other disturbances are kept).
    sensors : a built-in suite (``research``, ``hobby``, ``ideal``) replacing the card's
        whole [sensors] table.

    Raises ValueError naming the option and, for an unknown field, the valid keys at that
    level. The result still has to pass ``card_from_dict`` (``overridden_card`` does both).
    """
    data = _plain(card_data)
    if turbulence is not None:
        if turbulence not in TURBULENCE_LEVELS:
            raise ValueError(f"--turbulence must be one of {', '.join(TURBULENCE_LEVELS)}, "
                             f"got {turbulence!r}")
        kept = [d for d in data.get("disturbance", [])
                if not (isinstance(d, dict) and d.get("kind") == "turbulence")]
        if turbulence != "none":
            kept.append({"kind": "turbulence", "intensity": turbulence})
        data["disturbance"] = kept
        if not kept:
            del data["disturbance"]
    if sensors is not None:
        suites = (*SUITES, NO_SENSORS)
        if sensors not in suites:
            raise ValueError(f"--sensors must be one of {', '.join(suites)}, got {sensors!r}")
        data["sensors"] = {"suite": sensors}
    for assignment in assignments:
        key, sep, text = assignment.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set {assignment!r}: expected KEY=VALUE, e.g. condition.speed=60")
        _set_path(data, key.strip(), _override_value(text.strip()))
    return data


def overridden_card(card: Card, assignments: Sequence[str] = (), turbulence: str | None = None,
                    sensors: str | None = None) -> Card:
    """``card`` with ``override``'s changes, validated again by ``card_from_dict`` (every
    card check applies; a CardError names the overridden field). No change: ``card``."""
    if not assignments and turbulence is None and sensors is None:
        return card
    data = override(card.data, assignments, turbulence, sensors)
    where = f"{card.path} (with command-line overrides)"
    return card_from_dict(data, where)


def load_card(path: str | Path) -> Card:
    """Read and validate a card file (path or library name); CardError names line and field."""
    p = find_card(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CardError(str(p), None, None, f"cannot read the card: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise CardError(str(p), int(m.group(1)) if m else None, None,
                        f"TOML syntax error: {exc}") from None
    return card_from_dict(data, str(p), text)


def load_maneuvers(path: str | Path) -> tuple[str, tuple[InputDesign, ...]]:
    """A maneuver table: a TOML file of ``[[maneuver]]`` tables in the card's syntax (any
    kinds and surfaces, flown together), with an optional ``name`` (default the file's
    stem) and ``description``. Returns (name, maneuvers); CardError names the file, line
    and field."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise CardError(str(p), None, None, f"cannot read the maneuver table: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise CardError(str(p), int(m.group(1)) if m else None, None,
                        f"TOML syntax error: {exc}") from None
    chk = _Checker(str(p), text)
    for key in data:
        if key not in ("name", "description", "maneuver"):
            raise chk.fail(key, "unknown field in a maneuver table; allowed: name, "
                           "description, [[maneuver]]")
    if not data.get("maneuver"):
        raise chk.fail("maneuver", "is required: at least one [[maneuver]] table")
    name = data.get("name", p.stem)
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise chk.fail("name", f"must be letters, digits, '_', '.' or '-', got {name!r}")
    return name, _maneuvers(chk, data["maneuver"], math.inf)


# -- flying -----------------------------------------------------------------------------------


def sub_seed(seed: int, purpose: str) -> int:
    """An independent 32-bit seed for one random part of a flight (e.g. 'sensors')."""
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
    or TrimInputError (one that is not a condition)."""
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
    """The XML path of the card's aircraft with its [[effect]]s (written once, then reused)."""
    return augmented_aircraft(card.aircraft, card.augmentation, cache)


def augmented_aircraft(aircraft: str, effects: Sequence[Any], cache: Path | None = None) -> str:
    """The XML path of ``aircraft`` with the airframe and actuator ``effects`` (catalogue
    effects), written once into the cache folder, then reused."""
    return str(augment_cached(aircraft, tuple(effects), cache or AUGMENT_CACHE,
                              name=f"{aircraft}-augmented"))


__all__ = ["AUGMENT_CACHE", "Card", "CardError", "Condition", "FlightCondition", "augmented",
           "augmented_aircraft",
           "card_from_dict", "find_card", "fly_card", "library_cards", "load_card",
           "override", "overridden_card", "sub_seed"]
