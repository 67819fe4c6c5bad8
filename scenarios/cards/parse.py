"""Reading a card: the TOML file checked field by field into a ``Card``; every mistake is a
``CardError`` naming the file, the line and the field."""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from pathlib import Path
from typing import Any

from flightid.derivatives import is_derivative
from flightid.scenarios.cards.library import find_card
from flightid.scenarios.cards.schema import (
    A_PRIORI_FIELDS,
    CONDITION_FIELDS,
    NO_SENSORS,
    TOP_FIELDS,
    Card,
    CardError,
    field_path,
)
from flightid.scenarios.input_design import InputDesign
from flightid.scenarios.inputs import input_from_dict
from flightid.scenarios.toml_locate import line_index, line_of
from flightid.sim.effects.catalogue import CATALOGUE, SECTIONS
from flightid.sim.flight.disturbed import Gust, disturbance_from_dict, vibration_of
from flightid.sim.jsbsim.condition import FlightCondition
from flightid.sim.jsbsim.model import available
from flightid.sim.sensors.tables import suite_from_dict
from flightid.units import DEG

_FIELD = re.compile(r"field '([^']+)'")
_LEAD = re.compile(r"^([A-Za-z_][\w.\[\]]*): ")



class _Checker:
    """Raises CardError with file, line and field for a card being parsed."""

    def __init__(self, path: str, text: str | None) -> None:
        self.path = path
        self.index = line_index(text) if text else {}

    def fail(self, field_name: str, message: str) -> CardError:
        line = line_of(self.index, field_path(field_name)) if self.index else None
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
    """Validate a parsed card; ``text`` (the TOML source) lets errors name the line.

    Parameters
    ----------
    data : dict[str, Any]
        The parsed TOML card.
    path : str, optional
        File name used in errors.
    text : str or None, optional
        The card's TOML source; None gives no line numbers.

    Returns
    -------
    Card
        The validated card.
    """
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



def load_card(path: str | Path) -> Card:
    """Read and validate a card file (path or library name); CardError names line and field.

    Parameters
    ----------
    path : str or Path
        Card file path or library card name.

    Returns
    -------
    Card
        The validated card.
    """
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
    and field.

    Parameters
    ----------
    path : str or Path
        The maneuver table's TOML file.

    Returns
    -------
    tuple[str, tuple[InputDesign, ...]]
        (name, maneuvers).
    """
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
