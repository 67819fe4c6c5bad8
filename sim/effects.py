"""Sensor error effects: each a named dataclass of float parameters (SI) with ``apply``.

``apply(t, x, rng) -> x_measured`` acts on one channel sampled at times ``t`` (s); random
effects draw from ``rng`` only, so the output is fixed by the generator's seed. Every
parameter is a plain float with a name (``parameters()``), so the gap diagnosis can fit
an effect back; ``source`` says where a value comes from and is not a parameter.
``EFFECTS`` maps names to classes and ``effect_from_dict`` builds them from card tables
such as ``{effect = "bias", value = 0.01}`` (``value_deg`` for angles and rates in degrees,
``value_g`` for accelerations in g). ``Sample`` changes the time base: ``output_time``.

Filters (lag, second order, anti-alias) start in steady state at the first value and
need a uniform time grid.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy import signal

from flightid.units import DEG, G0


@dataclass(kw_only=True)
class NamedEffect:
    """A named, parametrised effect: the common form of sensor errors, mounting effects and
    disturbances, so the simulator can inject any of them and a diagnosis fit it back.

    ``parameters()`` are the float fields (SI), what can be fitted; string fields choose a
    form (e.g. a turbulence model); ``source`` says where the values come from.
    """

    name: ClassVar[str] = ""
    key: ClassVar[str] = "effect"  # the card-table key that names the effect
    source: str = dataclasses.field(default="", compare=False)

    def parameters(self) -> dict[str, float]:
        """Float parameters by name (SI units)."""
        return {
            f.name: float(value)
            for f in dataclasses.fields(self)
            if f.name != "source"
            and isinstance(value := getattr(self, f.name), int | float)
            and not isinstance(value, bool)
        }

    def to_dict(self) -> dict[str, Any]:
        """``{key: name, **fields}`` plus the source if any (inverse of the from-dict builders)."""
        d: dict[str, Any] = {self.key: self.name}
        d.update({f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                  if f.name != "source"})
        if self.source:
            d["source"] = self.source
        return d


@dataclass(kw_only=True)
class Effect(NamedEffect):
    """Base of the per-channel effects."""

    def apply(self, t: np.ndarray, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The measured signal on times ``t`` (s) given the input signal ``x``."""
        raise NotImplementedError


def _positive(value: float, field: str, name: str, strict: bool = True) -> None:
    ok = value > 0 if strict else value >= 0
    if not ok or np.isnan(value):
        raise ValueError(
            f"{name}: field {field!r} must be {'>' if strict else '>='} 0, got {value}"
        )


def uniform_dt(t: np.ndarray, who: str) -> float:
    """The sample interval (s) of a uniform grid; raises naming ``who`` otherwise."""
    if t.size < 2:
        raise ValueError(f"{who}: needs at least two samples")
    d = np.diff(t)
    if np.ptp(d) > 1e-6 * d.mean():
        raise ValueError(f"{who}: needs a uniformly sampled time vector (dt varies)")
    return float(d.mean())


def lti_filter(num: list[float], den: list[float], t: np.ndarray, x: np.ndarray, who: str):
    """Continuous transfer function num/den (s-domain) applied to ``x`` on a uniform grid.

    First-order-hold discretisation (exact for piecewise-linear input), initial
    condition the steady state at x[0] (unity DC gain assumed).
    """
    dt = uniform_dt(t, who)
    b, a, _ = signal.cont2discrete((num, den), dt, method="foh")
    b = np.atleast_1d(np.squeeze(b))
    zi = signal.lfilter_zi(b, a) * x[0]
    return signal.lfilter(b, a, x, zi=zi)[0]


@dataclass(kw_only=True)
class WhiteNoise(Effect):
    """Additive white Gaussian noise of standard deviation ``sigma`` (channel unit)."""

    name: ClassVar[str] = "noise"
    sigma: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.sigma, "sigma", self.name, strict=False)

    def apply(self, t, x, rng):
        return x + self.sigma * rng.standard_normal(np.shape(x))


@dataclass(kw_only=True)
class Bias(Effect):
    """Constant offset ``value`` (channel unit)."""

    name: ClassVar[str] = "bias"
    value: float = 0.0

    def apply(self, t, x, rng):
        return x + self.value


@dataclass(kw_only=True)
class Drift(Effect):
    """Bias growing linearly at ``rate`` (channel unit per s) from the first sample."""

    name: ClassVar[str] = "drift"
    rate: float = 0.0

    def apply(self, t, x, rng):
        return x + self.rate * (np.asarray(t) - t[0])


@dataclass(kw_only=True)
class RandomWalk(Effect):
    """Bias random walk (gyro drift, seed 003): increments N(0, sigma^2 dt).

    ``sigma`` in channel unit per sqrt(s) (rate random walk for a gyro); the bias is
    zero at the first sample.
    """

    name: ClassVar[str] = "random_walk"
    sigma: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.sigma, "sigma", self.name, strict=False)

    def apply(self, t, x, rng):
        steps = self.sigma * np.sqrt(np.diff(t)) * rng.standard_normal(max(len(t) - 1, 0))
        return x + np.concatenate([[0.0], np.cumsum(steps)])


@dataclass(kw_only=True)
class ScaleFactor(Effect):
    """Multiplicative scale ``factor`` (1 = none), e.g. a vane's K (seed 001)."""

    name: ClassVar[str] = "scale"
    factor: float = 1.0

    def apply(self, t, x, rng):
        return self.factor * x


@dataclass(kw_only=True)
class Quantization(Effect):
    """Rounding to the nearest multiple of ``resolution`` (channel unit, one count)."""

    name: ClassVar[str] = "quantize"
    resolution: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.resolution, "resolution", self.name, strict=False)

    def apply(self, t, x, rng):
        if self.resolution == 0:
            return x.copy()
        return np.round(x / self.resolution) * self.resolution


@dataclass(kw_only=True)
class Saturation(Effect):
    """Clipping to +- ``limit`` (channel unit): the sensor's range."""

    name: ClassVar[str] = "saturate"
    limit: float = np.inf

    def __post_init__(self) -> None:
        _positive(self.limit, "limit", self.name)

    def apply(self, t, x, rng):
        return np.clip(x, -self.limit, self.limit)


@dataclass(kw_only=True)
class Delay(Effect):
    """Pure time delay ``tau`` (s): x(t - tau), linear interpolation, x[0] before the start."""

    name: ClassVar[str] = "delay"
    tau: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.tau, "tau", self.name, strict=False)

    def apply(self, t, x, rng):
        return np.interp(np.asarray(t) - self.tau, t, x)


@dataclass(kw_only=True)
class Lag(Effect):
    """First-order lag 1 / (tau s + 1), ``tau`` in s (sensor or tubing time constant)."""

    name: ClassVar[str] = "lag"
    tau: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.tau, "tau", self.name, strict=False)

    def apply(self, t, x, rng):
        if self.tau == 0:
            return x.copy()
        return lti_filter([1.0], [self.tau, 1.0], t, x, self.name)


@dataclass(kw_only=True)
class SecondOrder(Effect):
    """Second-order dynamics wn^2 / (s^2 + 2 zeta wn s + wn^2): a flow vane (seed 000 App. 2)."""

    name: ClassVar[str] = "second_order"
    wn: float = 100.0  # rad/s
    zeta: float = 0.7

    def __post_init__(self) -> None:
        _positive(self.wn, "wn", self.name)
        _positive(self.zeta, "zeta", self.name)

    def apply(self, t, x, rng):
        w = self.wn
        return lti_filter([w * w], [1.0, 2 * self.zeta * w, w * w], t, x, self.name)


def antialias(t: np.ndarray, x: np.ndarray, cutoff: float, order: int, who: str) -> np.ndarray:
    """Causal Butterworth low-pass of ``order`` at ``cutoff`` (Hz) on a uniform grid."""
    dt = uniform_dt(t, who)
    if cutoff >= 0.5 / dt:
        raise ValueError(
            f"{who}: anti-alias cutoff {cutoff} Hz is at or above the Nyquist frequency "
            f"{0.5 / dt} Hz of the signal it filters"
        )
    sos, zi = _butter(int(order), float(cutoff), round(1.0 / dt, 9))
    return signal.sosfilt(sos, x, zi=zi * x[0])[0]


@functools.lru_cache(maxsize=64)
def _butter(order: int, cutoff: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Butterworth sections and their unit-step initial state (one design per suite rate)."""
    sos = signal.butter(order, cutoff, fs=fs, output="sos")
    return sos, signal.sosfilt_zi(sos)


@dataclass(kw_only=True)
class LowPass(Effect):
    """Causal Butterworth low-pass: ``cutoff`` (Hz), ``order`` (1, 2, ...)."""

    name: ClassVar[str] = "lowpass"
    cutoff: float = 10.0
    order: float = 2.0

    def __post_init__(self) -> None:
        _positive(self.cutoff, "cutoff", self.name)
        if self.order < 1 or self.order != int(self.order):
            raise ValueError(f"{self.name}: field 'order' must be a whole number >= 1")

    def apply(self, t, x, rng):
        return antialias(np.asarray(t), x, self.cutoff, int(self.order), self.name)


@dataclass(kw_only=True)
class Sample(Effect):
    """Sampling at ``rate`` (Hz) from the fast signal, first sample ``offset`` s after t[0].

    With ``antialias`` > 0 a causal Butterworth of ``order`` at that cutoff (Hz) filters
    first; with 0 there is none, so content above rate/2 (engine vibration) aliases as
    in a hobby IMU. Values between fast samples are linearly interpolated.
    """

    name: ClassVar[str] = "sample"
    rate: float = 100.0
    offset: float = 0.0
    antialias: float = 0.0
    order: float = 4.0

    def __post_init__(self) -> None:
        _positive(self.rate, "rate", self.name)
        _positive(self.offset, "offset", self.name, strict=False)
        _positive(self.antialias, "antialias", self.name, strict=False)
        if self.order < 1 or self.order != int(self.order):
            raise ValueError(f"{self.name}: field 'order' must be a whole number >= 1")

    def output_time(self, t: np.ndarray) -> np.ndarray:
        """Sample instants (s) within the span of ``t``."""
        t = np.asarray(t, float)
        n = int(np.floor((t[-1] - t[0] - self.offset) * self.rate + 1e-9)) + 1
        return t[0] + self.offset + np.arange(max(n, 0)) / self.rate

    def apply(self, t, x, rng):
        t = np.asarray(t, float)
        if self.antialias > 0:
            x = antialias(t, x, self.antialias, int(self.order), self.name)
        return np.interp(self.output_time(t), t, x)


EFFECTS: dict[str, type[Effect]] = {
    c.name: c
    for c in (
        WhiteNoise,
        Bias,
        Drift,
        RandomWalk,
        ScaleFactor,
        Quantization,
        Saturation,
        Delay,
        Lag,
        SecondOrder,
        LowPass,
        Sample,
    )
}

# parameters in the channel's own unit, which may be given as <name>_deg or <name>_g
CHANNEL_UNIT_PARAMS = {"sigma", "value", "rate", "resolution", "limit"}


def parse_params(
    cls: type, d: dict[str, Any], context: str, unit: str | None = None, skip=("effect",)
) -> dict[str, Any]:
    """Keyword arguments for ``cls`` from ``d``; ``_deg``/``_g`` suffixes convert to SI.

    ``unit`` is the unit of the channel the effect acts on (to check the suffix).
    Errors name ``context.field``.
    """
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    out: dict[str, Any] = {}
    for key, value in d.items():
        if key in skip:
            continue
        where = f"{context}.{key}" if context else key
        name, scale = key, 1.0
        for suffix, factor, needs in (("_deg", DEG, "rad"), ("_g", G0, "m/s^2")):
            if key.endswith(suffix) and key[: -len(suffix)] in fields:
                name = key[: -len(suffix)]
                scale = factor
                angle_field = fields[name].metadata.get("unit") == "rad"
                if name in CHANNEL_UNIT_PARAMS and not angle_field:
                    if unit is None or not unit.startswith(needs):
                        raise ValueError(
                            f"field {where!r}: {suffix} needs a channel in {needs}"
                            + (f"; this channel is in {unit}" if unit else "")
                        )
                elif not (angle_field and suffix == "_deg"):
                    raise ValueError(f"field {where!r}: {name} cannot be given as {suffix}")
        if name not in fields:
            raise ValueError(
                f"field {where!r} is not a parameter of {getattr(cls, 'name', cls.__name__)!r}; "
                f"allowed: {', '.join(sorted(fields))}"
            )
        if name in out:
            raise ValueError(f"field {where!r}: {name} given twice")
        if name == "source":
            if not isinstance(value, str):
                raise ValueError(f"field {where!r} must be a string")
            out[name] = value
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"field {where!r} must be a number, got {value!r}")
        out[name] = float(value) * scale
    return out


def effect_from_dict(d: dict[str, Any], context: str = "", unit: str | None = None) -> Effect:
    """Build a channel effect from ``{"effect": name, ...parameters}``; errors name the field."""
    if not isinstance(d, dict):
        raise ValueError(f"{context or 'effect'}: expected a table, got {type(d).__name__}")
    pre = f"{context}." if context else ""
    if "effect" not in d:
        raise ValueError(f"field {pre + 'effect'!r} is missing; one of {', '.join(EFFECTS)}")
    name = d["effect"]
    if name not in EFFECTS:
        raise ValueError(
            f"field {pre + 'effect'!r}: unknown effect {name!r}; known: {', '.join(EFFECTS)}"
        )
    cls = EFFECTS[name]
    kwargs = parse_params(cls, d, context, unit)
    try:
        return cls(**kwargs)
    except ValueError as exc:
        raise ValueError(f"{context}: {exc}") from None
