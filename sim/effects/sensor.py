"""Sensor errors: per-channel effects of the measurement chain (catalogue ``sensor``).

``apply(t, x, rng) -> x_measured`` acts on one channel sampled at times ``t`` (s); random
effects draw from ``rng`` only, so the output is fixed by the generator's seed. Every
parameter is a plain float with a name (``parameters()``), so the gap diagnosis can fit
an effect back; ``source`` says where a value comes from and is not a parameter.
``Sample`` changes the time base: ``output_time``.

Filters (lag, second order, anti-alias) start in steady state at the first value and
need a uniform time grid. A parameter at its neutral value leaves the signal unchanged;
for the bandwidths that is infinity (``saturate`` limit, ``lowpass`` cutoff,
``second_order`` wn, ``sample`` rate: an infinitely fast sampler is the signal itself).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy import signal

from flightid.sim.effects.base import Effect
from flightid.sim.effects.base import positive as _positive


def uniform_dt(t: np.ndarray, who: str) -> float:
    """The sample interval of a uniform grid.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    who : str
        Names the caller in messages.

    Returns
    -------
    float
        The interval, s.

    Raises
    ------
    ValueError
        Naming ``who`` with fewer than two samples or a varying interval.
    """
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

    Parameters
    ----------
    num, den : list of float
        Numerator and denominator coefficients, s-domain.
    t : numpy.ndarray
        Sample times, s; uniform.
    x : numpy.ndarray
        Input signal; same shape as ``t``.
    who : str
        Names the caller in messages.

    Returns
    -------
    numpy.ndarray
        Filtered signal, unit of ``x``; same shape.
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
    """Bias random walk (gyro drift, as in the Boomerang 60 paper): increments N(0, sigma^2 dt).

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
    """Multiplicative scale ``factor`` (1 = none), e.g. a vane's K (Cooper et al. 1990)."""

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
    """Second-order dynamics wn^2 / (s^2 + 2 zeta wn s + wn^2): a flow vane.

    Vane dynamics as measured by Sofyan, RMIT thesis (c. 1997), App. 2.

    ``wn`` = inf is an infinitely fast sensor: the signal unchanged.
    """

    name: ClassVar[str] = "second_order"
    wn: float = 100.0  # rad/s
    zeta: float = 0.7

    def __post_init__(self) -> None:
        _positive(self.wn, "wn", self.name)
        _positive(self.zeta, "zeta", self.name)

    def apply(self, t, x, rng):
        if math.isinf(self.wn):
            return np.array(x, float)
        w = self.wn
        return lti_filter([w * w], [1.0, 2 * self.zeta * w, w * w], t, x, self.name)


def antialias(t: np.ndarray, x: np.ndarray, cutoff: float, order: int, who: str) -> np.ndarray:
    """Causal Butterworth low-pass of ``order`` at ``cutoff`` on a uniform grid.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s; uniform.
    x : numpy.ndarray
        Input signal; same shape as ``t``.
    cutoff : float
        Cutoff frequency, Hz; below the Nyquist frequency.
    order : int
        Filter order.
    who : str
        Names the caller in messages.

    Returns
    -------
    numpy.ndarray
        Filtered signal, started at steady state on x[0]; unit and shape of ``x``.
    """
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
    """Causal Butterworth low-pass: ``cutoff`` (Hz; inf: no filter), ``order`` (1, 2, ...)."""

    name: ClassVar[str] = "lowpass"
    cutoff: float = 10.0
    order: float = 2.0

    def __post_init__(self) -> None:
        _positive(self.cutoff, "cutoff", self.name)
        if self.order < 1 or self.order != int(self.order):
            raise ValueError(f"{self.name}: field 'order' must be a whole number >= 1")

    def apply(self, t, x, rng):
        if math.isinf(self.cutoff):
            return np.array(x, float)
        return antialias(np.asarray(t), x, self.cutoff, int(self.order), self.name)


@dataclass(kw_only=True)
class Sample(Effect):
    """Sampling at ``rate`` (Hz) from the fast signal, first sample ``offset`` s after t[0].

    With ``antialias`` > 0 a causal Butterworth of ``order`` at that cutoff (Hz) filters
    first; with 0 there is none, so content above rate/2 (engine vibration) aliases as
    in a hobby IMU. Values between fast samples are linearly interpolated. ``rate`` = inf
    samples continuously: the fast signal itself (from ``offset`` on), no time-base change.
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
        if math.isinf(self.rate):
            return t[t >= t[0] + self.offset - 1e-12].copy()
        n = int(np.floor((t[-1] - t[0] - self.offset) * self.rate + 1e-9)) + 1
        return t[0] + self.offset + np.arange(max(n, 0)) / self.rate

    def apply(self, t, x, rng):
        t = np.asarray(t, float)
        if self.antialias > 0:
            x = antialias(t, x, self.antialias, int(self.order), self.name)
        return np.interp(self.output_time(t), t, x)
