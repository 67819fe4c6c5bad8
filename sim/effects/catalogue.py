"""The effect catalogue: every injectable effect declared once.

An entry (``Entry``) says what an effect is called, where it acts (``ActsOn``), what it
does in one line, its parameters (``Parameter``: name, unit, meaning, the default
magnitude for blind tests, the allowed range, and the neutral value at which it does
nothing), the string options that choose its form, what it changes in the data, and the
implementation that injects it: a class of this package, or a ``Reference`` (module,
attribute and parameter mapping) for the bridge's link faults and recorder clocks.

Where an effect acts decides how it is injected (docs/effects.md, "Where effects act"):
``sensor`` on one measured channel in the sensor chain, ``mounting`` on several channels
from where the sensors sit, ``vibration`` on the IMU from the engine speed (both in
``flightid.sim.sensors.suites.measure``), ``disturbance`` in the atmosphere JSBSim flies through
(``flightid.sim.flight.disturbed``), ``link`` and ``clock`` in the bridge, ``airframe`` and
``actuator`` written into a copy of the aircraft's JSBSim XML (``flightid.sim.augment``).

Cards name effects in three places (``SECTIONS``): a sensor channel's chain
(``effect = ...``), the sensor suite's mounting list (``effect = ...``) and
``[[disturbance]]`` (``kind = ...``), and ``[[effect]]`` (``name = ...``) for airframe and
actuator effects; ``CATALOGUE.lookup`` resolves each name to exactly
one entry and says where a name belongs if it is given in the wrong place.
``engine_vibration`` is one entry that cards accept in both the mounting list and
``[[disturbance]]``.

Units are SI; ``[ch]`` is the unit of the channel a sensor effect sits on (rad/s on a rate
gyro, m/s^2 on an accelerometer). Sensor effects' default magnitudes are sized for the
channel ``Entry.channel`` (a pitch-rate gyro). A parameter written ``<name>_deg`` in a
card is in degrees (angles, rates and [ch] on an angle channel), ``<name>_g`` in g.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from flightid.sim.effects.airframe import (
    AXES_CHOICES,
    DERIVATIVES,
    FORM_CHOICES,
    SURFACE_CHOICES,
    ActuatorBias,
    ActuatorLag,
    Backlash,
    CgOffset,
    ControlEffectiveness,
    Deadband,
    DerivativeDelta,
    InertiaScale,
    MassScale,
    RateLimit,
    TailIce,
    ThrustMoment,
)
from flightid.sim.effects.base import NamedEffect, Reference
from flightid.sim.effects.clock import RECORDER_CLOCK
from flightid.sim.effects.disturbance import INTENSITIES, TURBULENCE_MODELS, Gust, Turbulence, Wind
from flightid.sim.effects.link import link_fault
from flightid.sim.effects.mounting import MISALIGNMENT_AXES, LeverArm, Misalignment, Vanes
from flightid.sim.effects.sensor import (
    Bias,
    Delay,
    Drift,
    Lag,
    LowPass,
    Quantization,
    RandomWalk,
    Sample,
    Saturation,
    ScaleFactor,
    SecondOrder,
    WhiteNoise,
)
from flightid.sim.effects.vibration import AXES, EngineVibration
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
        return f"{lo}{_num(self.low)}, {_num(self.high)}{hi}"


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
    implementation: type[NamedEffect] | Reference
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
        if isinstance(self.implementation, Reference):
            return self.implementation.target
        return f"{self.implementation.__module__}:{self.implementation.__qualname__}"

    def resolve(self) -> Any:
        """The implementation object (a Reference's target is imported by name)."""
        if isinstance(self.implementation, Reference):
            return self.implementation.resolve()
        return self.implementation

    def build(self, values: Mapping[str, float] | None = None, **options: str) -> NamedEffect:
        """The effect object with parameter ``values`` (default: the blind-test magnitudes)."""
        if isinstance(self.implementation, Reference):
            raise TypeError(f"{self.name} is injected by {self.implementation.target}; "
                            f"use Entry.fields for its keyword arguments")
        values = self.defaults() if values is None else dict(values)
        return self.implementation(**values, **options)

    def fields(self, values: Mapping[str, float] | None = None) -> dict[str, float]:
        """The implementation's keyword arguments for ``values`` (the parameter mapping)."""
        values = self.defaults() if values is None else dict(values)
        if isinstance(self.implementation, Reference):
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
        if isinstance(self.implementation, Reference):
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


def _num(x: float) -> str:
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
                if not isinstance(e.implementation, Reference)}

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


# -- the declarations ------------------------------------------------------------------


def _p(name: str, unit: str, meaning: str, default: float, low: float = -INF,
       high: float = INF, neutral: float | None = 0.0, low_open: bool = False) -> Parameter:
    return Parameter(name, unit, meaning, default, low, high, neutral, low_open)


def _sensor(name: str, cls: type, description: str, *params: Parameter) -> Entry:
    return Entry(name, ActsOn.SENSOR, description, params, cls, ("q",), channel="q")


_VANE = "vane position from the CG, body {axis} (m)"
_SURFACE = Option("surface", SURFACE_CHOICES, "de", "the control surface (project signs)")


def _actuator(name: str, cls: type, description: str, changes: tuple[str, ...],
              *params: Parameter) -> Entry:
    return Entry(name, ActsOn.ACTUATOR, description, params, cls, changes, options=(_SURFACE,))

CATALOGUE = Catalogue((
    # -- sensor: one channel, in the order a chain usually applies them -------------------
    _sensor("noise", WhiteNoise, "additive white Gaussian noise",
            _p("sigma", CH, "standard deviation", 0.005, 0.0)),
    _sensor("bias", Bias, "constant offset (null shift)",
            _p("value", CH, "offset", 0.01)),
    _sensor("drift", Drift, "bias growing linearly from the first sample",
            _p("rate", f"{CH}/s", "growth rate of the bias", 0.002)),
    _sensor("random_walk", RandomWalk, "bias random walk (gyro rate random walk), zero at "
            "the first sample",
            _p("sigma", f"{CH}/sqrt(s)", "increments N(0, sigma^2 dt)", 0.002, 0.0)),
    _sensor("scale", ScaleFactor, "multiplicative scale-factor error (a vane's K, a gain "
            "error)",
            # (0, 2]: a gain error doubling the signal, or a sign or unit error, is no
            # scale factor (a vane's K is 1.0-1.3, Morelli & Klein 2016 §10.2)
            _p("factor", "1", "measured = factor x true", 1.05, 0.0, 2.0, neutral=1.0,
               low_open=True)),
    _sensor("quantize", Quantization, "rounding to whole counts of the converter",
            _p("resolution", CH, "one count (0: none)", 0.002, 0.0)),
    _sensor("saturate", Saturation, "clipping at the sensor's range",
            _p("limit", CH, "range +-limit (inf: unlimited); the default clips a pitch "
               "doublet's response", 0.05, 0.0, neutral=INF, low_open=True)),
    _sensor("delay", Delay, "pure time delay (tubing, processing, transmission)",
            _p("tau", "s", "delay", 0.05, 0.0)),
    _sensor("lag", Lag, "first-order lag 1 / (tau s + 1) (sensor or tubing time constant)",
            _p("tau", "s", "time constant", 0.05, 0.0)),
    _sensor("second_order", SecondOrder, "second-order sensor dynamics (a flow vane)",
            _p("wn", "rad/s", "natural frequency (inf: none)", 30.0, 0.0, neutral=INF,
               low_open=True),
            _p("zeta", "1", "damping ratio", 0.7, 0.0, neutral=None, low_open=True)),
    _sensor("lowpass", LowPass, "causal Butterworth low-pass filter",
            _p("cutoff", "Hz", "cutoff frequency (inf: none)", 5.0, 0.0, neutral=INF,
               low_open=True),
            _p("order", "1", "filter order (whole number)", 2.0, 1.0, neutral=None)),
    _sensor("sample", Sample, "sampling at a lower rate, optionally anti-aliased; "
            "aliases what lies above rate/2",
            _p("rate", "Hz", "sample rate (inf: continuous)", 25.0, 0.0, neutral=INF,
               low_open=True),
            _p("offset", "s", "first sample after the record's start", 0.0, 0.0),
            _p("antialias", "Hz", "anti-alias Butterworth cutoff (0: none)", 0.0, 0.0),
            _p("order", "1", "anti-alias filter order (whole number)", 4.0, 1.0, neutral=None)),
    # -- mounting ------------------------------------------------------------------------
    Entry("lever_arm", ActsOn.MOUNTING, "accelerometers away from the CG: tangential and "
          "centripetal accelerations of the rotation",
          (_p("x", "m", "accelerometer position from the CG, body x (forward)", 0.3),
           _p("y", "m", "accelerometer position from the CG, body y (right)", 0.05),
           _p("z", "m", "accelerometer position from the CG, body z (down)", 0.2)),
          LeverArm, ("ax", "ay", "az")),
    Entry("vanes", ActsOn.MOUNTING, "alpha/beta vanes away from the CG (rotation-induced "
          "flow) with upwash and sidewash flow amplification",
          (*(_p(f"{a}_{axis}", "m", f"{a} " + _VANE.format(axis=axis), d)
             for a in ("alpha", "beta") for axis, d in zip("xyz", (1.0, 0.0, 0.0), strict=True)),
           _p("upwash", "1", "alpha measured = (1 + upwash) x local alpha", 0.05, -1.0,
              low_open=True),
           _p("sidewash", "1", "beta measured = (1 + sidewash) x local beta", 0.05, -1.0,
              low_open=True)),
          Vanes, ("alpha", "beta")),
    Entry("misalignment", ActsOn.MOUNTING, "IMU triad (gyros and accelerometers) rotated "
          "about one body axis (mounting error)",
          # |angle| <= 0.1 rad (5.7 deg): a triad mounted visibly crooked; a bench
          # alignment leaves a few tenths of a degree (Jategaonkar 2015, ch. 10)
          (_p("angle", "rad", "rotation about the axis, right-handed", 0.02, -0.1, 0.1),),
          Misalignment, ("p", "r", "ax", "az"),
          options=(Option("axis", MISALIGNMENT_AXES, "y",
                          "body axis of the rotation (y: p and r, ax and az mixed)"),)),
    # -- vibration -------------------------------------------------------------------------
    Entry("engine_vibration", ActsOn.VIBRATION, "narrowband engine/propeller vibration "
          "lines on the IMU, following the rpm (aliases without an anti-alias filter)",
          (*(_p(a, "m/s^2", f"{a} amplitude at rpm_ref", d, 0.0)
             for a, d in zip(AXES[:3], (2.0, 2.0, 3.0), strict=True)),
           *(_p(a, "rad/s", f"{a} amplitude at rpm_ref", d, 0.0)
             for a, d in zip(AXES[3:], (2 * DEG, 2 * DEG, 1 * DEG), strict=True)),
           _p("harmonics", "1", "lines at 1..n x the rotation frequency (whole number)", 2.0,
              1.0, neutral=None),
           _p("harmonic_decay", "1", "relative amplitude of harmonic n: decay^(n-1)", 0.5,
              0.0, neutral=None),
           _p("blades", "1", "propeller blades: a blade-passing line (0: none)", 2.0, 0.0,
              neutral=None),
           _p("blade_amplitude", "1", "relative amplitude of the blade-passing line", 0.5,
              0.0, neutral=None),
           _p("gear_ratio", "1", "propeller turns per engine turn", 1.0, 0.0, neutral=None,
              low_open=True),
           _p("rpm_ref", "1/min", "engine speed of the amplitudes (0: amplitudes fixed)", 0.0,
              0.0, neutral=None),
           _p("exponent", "1", "amplitudes scale as (rpm/rpm_ref)^exponent", 0.0,
              neutral=None)),
          EngineVibration, AXES),
    # -- disturbance -----------------------------------------------------------------------
    Entry("wind", ActsOn.DISTURBANCE, "steady wind (NED, the direction the air moves "
          "towards); cards may give speed and from_deg instead",
          (_p("north", "m/s", "north component", -4.0),
           _p("east", "m/s", "east component", 3.0),
           _p("down", "m/s", "down component", 0.0)),
          Wind, ("wind_north", "wind_east", "north", "east")),
    Entry("gust", ActsOn.DISTURBANCE, "1-cosine discrete gust: rise, hold, fall "
          "(MIL-F-8785C 3.7.5)",
          (_p("start", "s", "time the gust begins", 1.0, 0.0, neutral=None),
           _p("rise", "s", "rise time (gust length / airspeed)", 0.5, 0.0, neutral=None,
              low_open=True),
           _p("hold", "s", "time at the peak", 0.0, 0.0, neutral=None),
           _p("fall", "s", "fall time", 0.5, 0.0, neutral=None, low_open=True),
           _p("north", "m/s", "peak north component", 0.0),
           _p("east", "m/s", "peak east component", 0.0),
           _p("down", "m/s", "peak down component (negative: up-gust)", -2.0)),
          Gust, ("wind_down", "alpha")),
    Entry("turbulence", ActsOn.DISTURBANCE, "continuous turbulence, Dryden or von Karman "
          "(MIL-F-8785C 3.7.2-3.7.4), or JSBSim's own",
          (_p("sigma", "m/s", "standard deviation, all axes (0 with no intensity: calm)",
              1.0, 0.0),
           _p("sigma_u", "m/s", "standard deviation along the heading (0: sigma)", 0.0, 0.0),
           _p("sigma_v", "m/s", "standard deviation to the right (0: sigma)", 0.0, 0.0),
           _p("sigma_w", "m/s", "standard deviation down (0: sigma)", 0.0, 0.0),
           _p("scale_length", "m", "scale length, all axes (0: from intensity and height)",
              300.0, 0.0, neutral=None),
           _p("scale_length_w", "m", "vertical scale length (0: scale_length)", 0.0, 0.0,
              neutral=None)),
          Turbulence, ("turb_u", "turb_v", "turb_w", "alpha", "beta"),
          options=(Option("model", TURBULENCE_MODELS, "dryden", "spectrum form"),
                   Option("intensity", ("", *INTENSITIES), "",
                          "MIL-F-8785C intensity by probability of exceedance; sets sigma "
                          "and scale lengths from the height"))),
    # -- airframe: written into a copy of the JSBSim XML (flightid.sim.augment) ----------------
    Entry("derivative_delta", ActsOn.AIRFRAME, "additive delta to one aerodynamic derivative "
          "(an extra JSBSim <function> term)",
          (_p("delta", "1/rad", "delta, per rad (per unit nondimensional rate for p q r "
              "alphadot)", 0.02),),
          DerivativeDelta, ("r", "beta"),
          options=(Option("derivative", DERIVATIVES, "Cn_beta",
                          "the derivative, C<coef>_<var> (flightid.derivatives)"),
                   Option("axes", AXES_CHOICES, "stability",
                          "axes of the delta: stability (CL CD CY, Cl Cm Cn, stability-axis "
                          "rates) or body (CX CY CZ, body rates)"),
                   Option("form", FORM_CHOICES, "linear",
                          "linear: delta x variable; even: delta x abs(variable), a term "
                          "even in the variable (one-sided slopes apart by 2 delta)"))),
    Entry("control_effectiveness", ActsOn.AIRFRAME, "every aerodynamic term reading a "
          "surface scaled (effectiveness loss, tail ice)",
          (_p("factor", "1", "scale of the surface's terms", 0.8, 0.0, neutral=1.0),),
          ControlEffectiveness, ("de", "q"), options=(_SURFACE,)),
    Entry("cg_offset", ActsOn.AIRFRAME, "CG moved (every mass item: CG, point masses, tanks)",
          # |shift| <= 0.5 m: a CG envelope spans some 15-20 % of the mean chord, 0.3-0.4 m
          # on the Twin Otter's 1.98 m chord (a judgement, wide for the project's aircraft)
          (_p("x", "m", "CG shift, body x (forward)", 0.05, -0.5, 0.5),
           _p("z", "m", "CG shift, body z (down)", 0.0, -0.5, 0.5)),
          CgOffset, ("de", "q")),
    Entry("mass_scale", ActsOn.AIRFRAME, "empty weight and point masses scaled (mass error)",
          # [0.5, 2]: an empty weight known to better than a factor of two (weighed)
          (_p("factor", "1", "mass scale factor", 1.1, 0.5, 2.0, neutral=1.0),),
          MassScale, ("alpha", "de")),
    Entry("inertia_scale", ActsOn.AIRFRAME, "moments of inertia scaled (Ixz by sqrt(ixx izz))",
          # [0.5, 2]: inertias estimated from radii of gyration are good to some 20-30 %;
          # a factor of two is no inertia error (a judgement)
          (_p("ixx", "1", "Ixx scale factor", 1.1, 0.5, 2.0, neutral=1.0),
           _p("iyy", "1", "Iyy scale factor", 1.1, 0.5, 2.0, neutral=1.0),
           _p("izz", "1", "Izz scale factor", 1.1, 0.5, 2.0, neutral=1.0)),
          InertiaScale, ("q", "p")),
    Entry("thrust_moment", ActsOn.AIRFRAME, "pitching moment proportional to thrust (thrust "
          "line, propwash)",
          # |arm| <= 1 m: a thrust line within a metre of the CG (nacelles, pylons)
          (_p("arm", "m", "N m per N of thrust, nose up positive", 0.1, -1.0, 1.0),),
          ThrustMoment, ("de",)),
    Entry("tail_ice", ActsOn.AIRFRAME, "horizontal-tail ice: pitching-moment terms reading the "
          "elevator, alpha, the pitch rate scaled (as twinotter-iced)",
          # (0, 1]: ice only takes effectiveness away (Batterson & O'Mara, NASA TM-4099,
          # 1989: elevator effectiveness, static stability and pitch damping all fall)
          (_p("elevator", "1", "scale of the pitching-moment terms reading the elevator "
              "(Cm_de)", 0.85, 0.0, 1.0, neutral=1.0, low_open=True),
           _p("stability", "1", "scale of the pitching-moment terms reading alpha (Cm_alpha)",
              0.9, 0.0, 1.0, neutral=1.0, low_open=True),
           _p("damping", "1", "scale of the pitching-moment terms reading q or alphadot "
              "(Cm_q, Cm_alphadot)", 0.9, 0.0, 1.0, neutral=1.0, low_open=True)),
          TailIce, ("q", "de")),
    # -- actuator: JSBSim <actuator> components (flightid.sim.augment) -------------------------
    _actuator("actuator_lag", ActuatorLag, "first-order lag 1/(tau s + 1) in series with the "
              "surface actuator", ("de", "q"),
              _p("tau", "s", "time constant", 0.05, 0.0)),
    _actuator("rate_limit", RateLimit, "surface rate limit in series with the actuator",
              ("de", "q"),
              _p("rate", "rad/s", "rate limit (inf: none)", 20 * DEG, 0.0, neutral=INF,
                 low_open=True)),
    _actuator("deadband", Deadband, "deadband (around zero) between the measured surface "
              "and the aerodynamics", ("q",),
              _p("width", "rad", "full width of the band", 0.5 * DEG, 0.0)),
    _actuator("backlash", Backlash, "backlash (hysteresis) between the measured surface and "
              "the aerodynamics", ("q",),
              _p("width", "rad", "full width of the hysteresis", 0.5 * DEG, 0.0)),
    _actuator("actuator_bias", ActuatorBias, "rigging bias: the aerodynamics see the measured "
              "surface plus a bias", ("de",),
              _p("bias", "rad", "aerodynamic minus measured deflection", 0.5 * DEG)),
    # -- link: the bridge's LinkFaults ---------------------------------------------------------
    Entry("corrupt", ActsOn.LINK, "bytes corrupted on the link (packets then fail their CRC)",
          (_p("probability", "1", "probability per byte", 1e-3, 0.0, 1.0),),
          link_fault("corrupt", "probability"), (PACKET_BYTES,)),
    Entry("drop", ActsOn.LINK, "whole packets lost on the link",
          (_p("probability", "1", "probability per packet", 0.01, 0.0, 1.0),),
          link_fault("drop", "probability"), (PACKET_BYTES,)),
    Entry("latency", ActsOn.LINK, "constant delivery delay of every packet",
          (_p("delay", "s", "delivery delay", 0.05, 0.0),),
          link_fault("latency", "delay"), (ARRIVAL_TIMES,)),
    Entry("jitter", ActsOn.LINK, "random delivery delay (packets stay in order)",
          (_p("sigma", "s", "standard deviation of the delay", 0.005, 0.0),),
          link_fault("jitter", "sigma"), (ARRIVAL_TIMES,)),
    # -- clock: the bridge's recorder streams ----------------------------------------------------
    Entry("clock", ActsOn.CLOCK, "a recorder's own clock: t_local = offset + (1 + drift) t",
          (_p("offset", "s", "recorder clock at sim time 0 (powered on before)", 0.84, 0.0),
           _p("drift", "1", "fractional rate error (150e-6 = 150 ppm)", 150e-6, -1.0,
              low_open=True)),
          RECORDER_CLOCK, (TIME_STAMPS,)),
))

# What an airframe can have: the range of each derivative (per rad; per unit
# nondimensional rate for p q r alphadot; project control signs, body or stability axes) a
# ``derivative_delta`` may move the model's value to. A judgement with wide margins: the
# bounds enclose the project's aircraft and the stock JSBSim DHC6 and c172p at their test
# conditions (measured with flightid.sim.jsbsim.truth.derivatives; e.g. Cm_alphadot -8.0 to 0,
# Cm_q -34.8 to -9.96, CL_alpha 4.01 to 5.62) and the light-aircraft to jet-transport
# values compiled by Heffley & Jewell (NASA CR-2144, 1972); a lift slope above 7.5 per
# rad exceeds thin-aerofoil theory's 2 pi of an infinite wing (Anderson 2017, §4.7) plus
# what fuselage and tail add. A derivative not listed is unbounded.
DERIVATIVE_RANGES: dict[str, tuple[float, float]] = {
    "CL_alpha": (0.0, 7.5), "CL_q": (-10.0, 40.0), "CL_alphadot": (-10.0, 20.0),
    "CL_de": (0.0, 1.5), "CD_alpha": (-1.0, 2.0), "CD_q": (-5.0, 5.0), "CD_de": (-0.3, 0.3),
    "Cm_alpha": (-4.0, 0.5), "Cm_q": (-80.0, 0.0), "Cm_alphadot": (-30.0, 5.0),
    "Cm_de": (-5.0, 0.0),
    "CY_beta": (-2.0, 0.0), "CY_p": (-1.0, 1.0), "CY_r": (-1.0, 2.0), "CY_da": (-0.5, 0.5),
    "CY_dr": (-0.1, 1.0),
    "Cl_beta": (-0.5, 0.1), "Cl_p": (-1.5, 0.0), "Cl_r": (-0.3, 0.8), "Cl_da": (-0.6, 0.05),
    "Cl_dr": (-0.15, 0.15),
    "Cn_beta": (-0.1, 0.8), "Cn_p": (-0.5, 0.3), "Cn_r": (-1.5, 0.05), "Cn_da": (-0.15, 0.15),
    "Cn_dr": (-0.5, 0.05),
}

# the card sections' views of the catalogue (name -> class)
EFFECTS: dict[str, type] = CATALOGUE.classes(ActsOn.SENSOR)


def effect_from_dict(d: dict[str, Any], context: str = "", unit: str | None = None):
    """Build a channel effect from ``{"effect": name, ...parameters}``; errors name the field.

    ``unit`` is the unit of the channel it acts on (for ``_deg``/``_g`` parameters).
    """
    return CATALOGUE.from_dict(d, "channel", context, unit)


def listing(where: ActsOn | str | None = None) -> list[dict[str, Any]]:
    """The catalogue as plain, JSON-safe data (non-finite numbers as "inf"/"-inf")."""
    entries = CATALOGUE.acting_on(ActsOn(where)) if where else list(CATALOGUE.values())
    return [{
        "name": e.name,
        "acts_on": str(e.acts_on),
        "description": e.description,
        "parameters": [{
            "name": p.name, "unit": p.unit, "meaning": p.meaning,
            "default": _json(p.default), "neutral": _json(p.neutral),
            "low": _json(p.low), "high": _json(p.high), "range": p.range_text(),
            "sizes": p.sizes,
        } for p in e.parameters],
        "options": [{"name": o.name, "choices": list(o.choices), "default": o.default,
                     "meaning": o.meaning} for o in e.options],
        "changes": list(e.changes),
        "sized_for_channel": e.channel,
        "implementation": e.implementation_name(),
        "parameter_mapping": (e.implementation.mapping()
                              if isinstance(e.implementation, Reference) else {}),
        "inject": e.how(),
    } for e in entries]


def markdown_table() -> str:
    """The catalogue as a Markdown table (docs/effects.md holds it; a test keeps it current)."""
    rows = ["| name | acts on | parameters: default (blind tests), allowed range | "
            "description | injected by |",
            "|---|---|---|---|---|"]
    for e in CATALOGUE.values():
        params = []
        for p in e.parameters:
            unit = "" if p.unit == "1" else f" {p.unit}"
            params.append(f"`{p.name}` = {_num(p.default)}{unit}, {p.range_text()}")
        params += [f"`{o.name}`: {', '.join(repr(c) for c in o.choices)}" for o in e.options]
        rows.append(f"| `{e.name}` | {e.acts_on} | {'<br>'.join(params)} | {e.description} "
                    f"| `{e.how()}` |")
    return "\n".join(rows) + "\n"


def _json(x: float | None) -> float | str | None:
    if x is None or math.isfinite(x):
        return x
    return "inf" if x > 0 else "-inf"


__all__ = ["ARRIVAL_TIMES", "CATALOGUE", "CH", "DERIVATIVE_RANGES", "EFFECTS", "PACKET_BYTES",
           "RESERVED", "SECTIONS", "TIME_STAMPS", "WHERE", "ActsOn", "Catalogue", "Entry", "Option",
           "Parameter", "Section", "effect_from_dict", "listing", "markdown_table"]
