"""The schema of the effect catalogue: where an effect acts (``ActsOn``), its parameters
(``Parameter``: name, unit, meaning, the default magnitude for blind tests, the allowed
range, the neutral value at which it does nothing) and options (``Option``), the card
sections that name effects (``Section``), one declaration (``Entry``) and the catalogue
that looks names up (``Catalogue``).

Units are SI; ``[ch]`` is the unit of the channel a sensor effect sits on (rad/s on a rate
gyro, m/s^2 on an accelerometer). A parameter written ``<name>_deg`` in a card is in
degrees (angles, rates and [ch] on an angle channel), ``<name>_g`` in g.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from flightid.sim.effects.base import ExternalImplementation, NamedEffect
from flightid.units import DEG, G0

INF = math.inf
CH = "[ch]"  # the unit of the channel a sensor effect sits on

# what link and clock effects change (record-level effects name record channels)
PACKET_BYTES = "packet bytes"
ARRIVAL_TIMES = "packet arrival times"
TIME_STAMPS = "message time stamps"


class ActsOn(StrEnum):
    """Where an effect acts, which decides how it is injected."""

    SENSOR = "sensor"  # one measured channel, in the sensor chain
    MOUNTING = "mounting"  # several channels at once, from where the sensors sit
    DISTURBANCE = "disturbance"  # the atmosphere the aircraft flies through
    VIBRATION = "vibration"  # engine/propeller vibration on the IMU, from the rpm
    LINK = "link"  # the bridge's telemetry link
    CLOCK = "clock"  # a recorder's clock
    AIRFRAME = "airframe"  # aerodynamics, mass properties (an augmented JSBSim XML)
    ACTUATOR = "actuator"  # lag, rate limit, deadband, backlash, bias (JSBSim XML)


# places without effects yet (none since airframe and actuator effects exist)
RESERVED: frozenset[ActsOn] = frozenset()

WHERE: dict[ActsOn, str] = {
    ActsOn.SENSOR: "one measured channel (sensor chain)",
    ActsOn.MOUNTING: "several channels from where the sensors sit",
    ActsOn.DISTURBANCE: "the atmosphere flown through",
    ActsOn.VIBRATION: "the IMU channels, from the engine speed",
    ActsOn.LINK: "the bridge's packets",
    ActsOn.CLOCK: "a recorder's time stamps",
    ActsOn.AIRFRAME: "the aircraft model (augmented JSBSim XML)",
    ActsOn.ACTUATOR: "the control actuators (augmented JSBSim XML)",
}


@dataclass(frozen=True)
class Parameter:
    """One parameter of an effect.

    ``default`` is the magnitude for blind tests; ``low``..``high`` the allowed range
    (``low_open``: low itself excluded); ``neutral`` the value at which the effect leaves
    the data unchanged (its zero magnitude; may be inf, e.g. an unlimited range), None for
    a parameter that shapes the effect without sizing it (kept at ``default``).
    """

    name: str
    unit: str
    meaning: str
    default: float
    low: float = -INF
    high: float = INF
    neutral: float | None = 0.0
    low_open: bool = False

    @property
    def zero(self) -> float:
        """The value at zero magnitude."""
        return self.default if self.neutral is None else self.neutral

    @property
    def sizes(self) -> bool:
        """Whether the parameter sizes the effect (has a neutral value)."""
        return self.neutral is not None

    def allows(self, value: float) -> bool:
        """Whether ``value`` is in the allowed range (infinity only as the neutral value)."""
        if math.isnan(value) or (math.isinf(value) and value != self.neutral):
            return False
        above = value > self.low if self.low_open else value >= self.low
        return above and value <= self.high

    def range_text(self) -> str:
        """The allowed range as an interval, e.g. ``[0, 1]`` or ``(0, inf]``."""
        lo = "(" if self.low_open or math.isinf(self.low) else "["
        hi = "]" if self.neutral == self.high or not math.isinf(self.high) else ")"
        return f"{lo}{number_text(self.low)}, {number_text(self.high)}{hi}"


@dataclass(frozen=True)
class Option:
    """A string field that chooses an effect's form (not fitted)."""

    name: str
    choices: tuple[str, ...]
    default: str
    meaning: str


@dataclass(frozen=True)
class Section:
    """A place in a flight card that names effects: the key and the entries it takes."""

    name: str
    key: str  # the table key that names the effect
    label: str  # what the messages call such an effect
    acts_on: tuple[ActsOn, ...]
    form: str  # how a card gives one, with {name} for the entry


SECTIONS: dict[str, Section] = {
    s.name: s for s in (
        Section("channel", "effect", "effect", (ActsOn.SENSOR,),
                '[sensors.channels] <channel> = [{{effect = "{name}", ...}}]'),
        Section("mounting", "effect", "mounting effect", (ActsOn.MOUNTING, ActsOn.VIBRATION),
                '[sensors] mounting = [{{effect = "{name}", ...}}]'),
        Section("disturbance", "kind", "disturbance", (ActsOn.DISTURBANCE, ActsOn.VIBRATION),
                '[[disturbance]] kind = "{name}"'),
        Section("effect", "name", "airframe or actuator effect",
                (ActsOn.AIRFRAME, ActsOn.ACTUATOR), '[[effect]] name = "{name}"'),
    )
}
# how an effect that no card section takes is injected
ELSEWHERE: dict[ActsOn, str] = {
    ActsOn.LINK: "the bridge: flightid bridge serve --faults {name}=<value>",
    ActsOn.CLOCK: "the bridge: a recorder stream's clock_offset and clock_drift "
                  "(flightid bridge serve --profile boomerang)",
}


@dataclass(frozen=True)
class Entry:
    """One injectable effect, declared once."""

    name: str
    acts_on: ActsOn
    description: str
    parameters: tuple[Parameter, ...]
    implementation: type[NamedEffect] | ExternalImplementation
    changes: tuple[str, ...]  # the record channels (or link/clock data) it changes
    options: tuple[Option, ...] = ()
    channel: str = ""  # sensor effects: the channel the default magnitudes are sized for

    def parameter(self, name: str) -> Parameter:
        """The parameter called ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"{self.name} has no parameter {name!r}; "
                       f"it has {', '.join(p.name for p in self.parameters)}")

    def defaults(self) -> dict[str, float]:
        """Parameter values for a blind test (the default magnitudes)."""
        return {p.name: p.default for p in self.parameters}

    def zeros(self) -> dict[str, float]:
        """Parameter values at zero magnitude: the effect leaves the data unchanged."""
        return {p.name: p.zero for p in self.parameters}

    def implementation_name(self) -> str:
        """``module:attribute`` of the implementation."""
        if isinstance(self.implementation, ExternalImplementation):
            return self.implementation.target
        return f"{self.implementation.__module__}:{self.implementation.__qualname__}"

    def resolve(self) -> Any:
        """The implementation object (an ExternalImplementation's target is imported by name)."""
        if isinstance(self.implementation, ExternalImplementation):
            return self.implementation.resolve()
        return self.implementation

    def build(self, values: Mapping[str, float] | None = None, **options: str) -> NamedEffect:
        """The effect object with parameter ``values`` (default: the blind-test magnitudes)."""
        if isinstance(self.implementation, ExternalImplementation):
            raise TypeError(f"{self.name} is injected by {self.implementation.target}; "
                            f"use Entry.fields for its keyword arguments")
        values = self.defaults() if values is None else dict(values)
        return self.implementation(**values, **options)

    def fields(self, values: Mapping[str, float] | None = None) -> dict[str, float]:
        """The implementation's keyword arguments for ``values`` (the parameter mapping)."""
        values = self.defaults() if values is None else dict(values)
        if isinstance(self.implementation, ExternalImplementation):
            return self.implementation.kwargs(values)
        return {k: float(v) for k, v in values.items()}

    def sections(self) -> tuple[Section, ...]:
        """The card sections that take this effect."""
        return tuple(s for s in SECTIONS.values() if self.acts_on in s.acts_on)

    def how(self) -> str:
        """How a card (or the bridge) injects it, one line."""
        forms = [s.form.format(name=self.name) for s in self.sections()]
        if not forms and self.acts_on in ELSEWHERE:
            forms = [ELSEWHERE[self.acts_on].format(name=self.name)]
        return "; or ".join(forms)

    # -- card tables ---------------------------------------------------------------------

    def parse(self, d: Mapping[str, Any], context: str = "", unit: str | None = None,
              skip: tuple[str, ...] = ("effect",)) -> dict[str, Any]:
        """Keyword arguments (SI) from a card table; errors name ``context.field``.

        ``<name>_deg`` converts degrees for angle parameters (rad, rad/s) and for [ch]
        parameters on an angle channel; ``<name>_g`` converts g for m/s^2 parameters and
        [ch] parameters on an acceleration channel. ``unit`` is the channel's unit.
        """
        params = {p.name: p for p in self.parameters}
        options = {o.name: o for o in self.options}
        allowed = sorted({*params, *options, "source"})
        out: dict[str, Any] = {}
        for key, value in d.items():
            if key in skip:
                continue
            where = f"{context}.{key}" if context else key
            name, scale = key, 1.0
            for suffix, factor, needs in (("_deg", DEG, "rad"), ("_g", G0, "m/s^2")):
                if key.endswith(suffix) and key[: -len(suffix)] in params:
                    name, scale = key[: -len(suffix)], factor
                    p_unit = params[name].unit
                    if p_unit.startswith(CH):
                        if unit is None or not unit.startswith(needs):
                            raise ValueError(
                                f"field {where!r}: {suffix} needs a channel in {needs}"
                                + (f"; this channel is in {unit}" if unit else "")
                            )
                    elif not p_unit.startswith(needs):
                        raise ValueError(f"field {where!r}: {name} cannot be given as {suffix}")
            if name not in params and name not in options and name != "source":
                raise ValueError(f"field {where!r} is not a parameter of {self.name!r}; "
                                 f"allowed: {', '.join(allowed)}")
            if name in out:
                raise ValueError(f"field {where!r}: {name} given twice")
            if name == "source" or name in options:
                if not isinstance(value, str):
                    raise ValueError(f"field {where!r} must be a string, got {value!r}")
                out[name] = value
                continue
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"field {where!r} must be a number, got {value!r}")
            if not math.isfinite(value) and not (value == params[name].neutral):
                raise ValueError(f"field {where!r} must be finite, got {value!r}")
            out[name] = float(value) * scale
        return out

    def check(self, values: Mapping[str, Any], context: str = "") -> None:
        """Raise naming ``context.field`` if a parameter value is outside its allowed range."""
        for p in self.parameters:
            if p.name in values and not p.allows(values[p.name]):
                where = f"{context}.{p.name}" if context else p.name
                unit = "" if p.unit == "1" else f" {p.unit}"
                raise ValueError(f"field {where!r}: {values[p.name]:g} is outside the allowed "
                                 f"range {p.range_text()}{unit} of {self.name}.{p.name}")

    def from_dict(self, d: Mapping[str, Any], context: str = "", unit: str | None = None,
                  skip: tuple[str, ...] = ("effect",)) -> NamedEffect:
        """The effect from a card table (``skip``: the key naming it); errors name the field."""
        if isinstance(self.implementation, ExternalImplementation):
            raise ValueError(f"{context or self.name}: {self.name} acts on the {self.acts_on} "
                             f"and is injected by {self.how()}")
        kwargs = self.parse(d, context, unit, skip)
        try:
            effect = self.implementation(**kwargs)
        except ValueError as exc:
            msg = str(exc)
            if context and msg.startswith("field '"):
                rest = msg[len("field '"):]
                raise ValueError(f"field '{context}.{rest}") from None
            raise ValueError(f"{context}: {msg}" if context else msg) from None
        self.check(kwargs, context)
        return effect


def number_text(x: float) -> str:
    """A number as the catalogue prints it (inf as inf).

    Parameters
    ----------
    x : float
        The number.

    Returns
    -------
    str
        ``format(x, 'g')``, or "inf"/"-inf".
    """
    return ("-inf" if x < 0 else "inf") if math.isinf(x) else f"{x:g}"


class Catalogue(Mapping[str, Entry]):
    """The entries by name, in declaration order; names are unique across all of them."""

    def __init__(self, entries: tuple[Entry, ...]) -> None:
        self._entries: dict[str, Entry] = {}
        for e in entries:
            if e.name in self._entries:
                raise ValueError(f"effect {e.name!r} declared twice")
            self._entries[e.name] = e

    def __getitem__(self, name: str) -> Entry:
        return self._entries[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def acting_on(self, *where: ActsOn) -> list[Entry]:
        """The entries that act on any of ``where``, in declaration order."""
        return [e for e in self._entries.values() if e.acts_on in where]

    def classes(self, *where: ActsOn) -> dict[str, type]:
        """Name -> implementing class for the entries acting on ``where``."""
        return {e.name: e.implementation for e in self.acting_on(*where)
                if not isinstance(e.implementation, ExternalImplementation)}

    def of(self, effect: NamedEffect | type) -> Entry:
        """The entry an effect object (or class) implements."""
        cls = effect if isinstance(effect, type) else type(effect)
        for e in self._entries.values():
            if e.implementation is cls:
                return e
        raise KeyError(f"{cls.__name__} is not in the effect catalogue")

    def lookup(self, name: Any, section: str, field: str = "") -> Entry:
        """The entry a card names in ``section`` (``SECTIONS``); errors name ``field``.

        An unknown name lists the valid ones; a catalogue name given in the wrong place
        says where it belongs.
        """
        sec = SECTIONS[section]
        valid = [e.name for e in self.acting_on(*sec.acts_on)]
        entry = self._entries.get(name) if isinstance(name, str) else None
        if entry is not None and entry.acts_on in sec.acts_on:
            return entry
        pre = f"field {field!r}" if field else f"{sec.label} {name!r}"
        if entry is None:
            raise ValueError(f"{pre}: unknown {sec.label} {name!r}; known: {', '.join(valid)}")
        raise ValueError(f"{pre}: {name!r} is a {entry.acts_on} effect (acts on "
                         f"{WHERE[entry.acts_on]}), not one of this place; give it as "
                         f"{entry.how()}. Known here: {', '.join(valid)}")

    def lookup_table(self, d: Any, section: str, context: str = "") -> Entry:
        """The entry a card table names with its section's key (``effect`` or ``kind``)."""
        sec = SECTIONS[section]
        field = f"{context}.{sec.key}" if context else sec.key
        if not isinstance(d, Mapping):
            raise ValueError(f"{context or sec.label}: expected a table, got {type(d).__name__}")
        if sec.key not in d:
            valid = [e.name for e in self.acting_on(*sec.acts_on)]
            raise ValueError(f"field {field!r} is missing; one of {', '.join(valid)}")
        return self.lookup(d[sec.key], section, field)

    def from_dict(self, d: Any, section: str, context: str = "",
                  unit: str | None = None) -> NamedEffect:
        """Build the effect a card table in ``section`` describes; errors name the field."""
        entry = self.lookup_table(d, section, context)
        return entry.from_dict(d, context, unit, skip=(SECTIONS[section].key,))


