"""Atmospheric disturbances (catalogue ``disturbance``): steady wind, discrete gusts and
continuous turbulence, each a named dataclass of float parameters (SI).

How they reach JSBSim is ``flightid.sim.flight.disturbed``: ``wind`` through the flight core's
``Atmosphere``; ``gust`` (1-cosine, MIL-F-8785C 3.7.5) and ``turbulence`` (Dryden or von
Karman, MIL-F-8785C 3.7.2-3.7.4; von Karman by the rational fits of MIL-HDBK-1797) as
time series written into JSBSim's gust properties; ``model = "jsbsim"`` uses JSBSim's own
MIL-F-8785C Dryden generator instead.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy import linalg, signal

from flightid.sim.effects.base import NamedEffect
from flightid.units import FT, KT

# -- MIL-F-8785C turbulence intensities and scale lengths ------------------------------

# probability of exceedance for the named intensities (MIL-F-8785C 3.7.2.1, Fig. 7)
INTENSITIES: dict[str, float] = {"light": 1e-2, "moderate": 1e-3, "severe": 1e-5}
# wind speed at 20 ft for the low-altitude model (MIL-F-8785C 3.7.3.4), knots
W20_KT: dict[str, float] = {"light": 15.0, "moderate": 30.0, "severe": 45.0}
# JSBSim's severity index (atmosphere/turbulence/milspec/severity) for each intensity
JSBSIM_SEVERITY: dict[str, int] = {"light": 3, "moderate": 4, "severe": 6}
# MIL-F-8785C Fig. 7: sigma (ft/s) against altitude (ft) for POE 1e-2, 1e-3, 1e-5
# (the same digitisation JSBSim uses in FGWinds)
_POE_ALT_FT = np.array([500.0, 1750, 3750, 7500, 15000, 25000, 35000, 45000, 55000, 65000,
                        75000, 80000])
_POE_SIGMA_FPS = {
    "light": np.array([6.6, 6.9, 7.4, 6.7, 4.6, 2.7, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0]),
    "moderate": np.array([8.6, 9.6, 10.6, 10.1, 8.0, 6.6, 5.0, 4.2, 2.7, 0.0, 0.0, 0.0]),
    "severe": np.array([15.6, 17.6, 23.0, 23.6, 22.1, 20.0, 16.0, 15.1, 12.1, 7.9, 6.2, 5.1]),
}
TURBULENCE_MODELS = ("dryden", "von_karman", "jsbsim")


def mil_f_8785c(intensity: str, h_agl_m: float, form: str = "dryden"
                ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Turbulence intensities and scale lengths at height h_agl_m above ground.

    MIL-F-8785C 3.7.2-3.7.3: below 1000 ft L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2,
    sigma_w = 0.1 W20, sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4 (h in ft,
    clipped at 10 ft); above 2000 ft L = 1750 ft (Dryden) or 2500 ft (von Karman) and sigma
    from Fig. 7 by probability of exceedance; linear in h between.

    Parameters
    ----------
    intensity : str
        Turbulence intensity, one of ``INTENSITIES``.
    h_agl_m : float
        Height above ground, m.
    form : str, optional
        "dryden" (default) or "von_karman"; sets the scale length above 2000 ft.

    Returns
    -------
    tuple of tuple of float
        ((sigma_u, sigma_v, sigma_w) m/s, (L_u, L_v, L_w) m).

    Raises
    ------
    ValueError
        For an unknown intensity.
    """
    if intensity not in INTENSITIES:
        raise ValueError(f"field 'intensity': {intensity!r} is not one of {', '.join(INTENSITIES)}")
    h = max(h_agl_m / FT, 10.0)
    w20 = W20_KT[intensity] * KT / FT
    high_l = 2500.0 if form == "von_karman" else 1750.0
    high_s = float(np.interp(h, _POE_ALT_FT, _POE_SIGMA_FPS[intensity]))

    def low(hh: float) -> tuple[float, float, float, float]:
        k = 0.177 + 0.000823 * hh
        sw = 0.1 * w20
        return sw / k**0.4, sw, hh / k**1.2, hh

    if h <= 1000.0:
        su, sw, lu, lw = low(h)
    else:
        su0, sw0, lu0, lw0 = low(1000.0)
        f = min((h - 1000.0) / 1000.0, 1.0)
        su, sw = su0 + f * (high_s - su0), sw0 + f * (high_s - sw0)
        lu, lw = lu0 + f * (high_l - lu0), lw0 + f * (high_l - lw0)
    return (su * FT, su * FT, sw * FT), (lu * FT, lu * FT, lw * FT)


def _shape(form: str, axis: str, L: float, V: float) -> tuple[list[float], list[float]]:
    """Numerator and denominator (powers of s, highest first) of the turbulence filter.

    Dryden (MIL-F-8785C 3.7.4): u 1 / (1 + a s); v, w (1 + sqrt(3) a s) / (1 + a s)^2,
    a = L / V. Von Karman, rational fits of MIL-HDBK-1797 (as in MATLAB's Aerospace
    Blockset), written with MIL-F-8785C's L (= 2 L_v of the handbook): u (1 + 0.25 a s) /
    (1 + 1.357 a s + 0.1987 a^2 s^2); v, w (1 + 2.7478 a s + 0.3398 a^2 s^2) /
    (1 + 2.9958 a s + 1.9754 a^2 s^2 + 0.1539 a^3 s^3). Gains are set by the variance.
    """
    a = L / V
    if form == "dryden":
        if axis == "u":
            return [1.0], [a, 1.0]
        return [math.sqrt(3.0) * a, 1.0], [a * a, 2 * a, 1.0]
    if axis == "u":
        return [0.25 * a, 1.0], [0.1987 * a * a, 1.357 * a, 1.0]
    return ([0.3398 * a * a, 2.7478 * a, 1.0],
            [0.1539 * a**3, 1.9754 * a * a, 2.9958 * a, 1.0])


def filtered_noise(num: Sequence[float], den: Sequence[float], sigma: float, n: int,
                   rate_hz: float, rng: np.random.Generator, settle_s: float) -> np.ndarray:
    """n samples of white noise through num/den (s-domain), scaled to standard deviation sigma.

    Bilinear (Tustin) discretisation as in Yeager 1998 (NASA CR-1998-206937); the gain is
    set from the exact stationary variance of the discrete filter (discrete Lyapunov
    equation), so the process has variance sigma^2 whatever the spectrum's constant.

    Parameters
    ----------
    num, den : sequence of float
        Numerator and denominator of the shaping filter, s-domain.
    sigma : float
        Standard deviation of the output, in the output's unit.
    n : int
        Number of samples.
    rate_hz : float
        Sample rate, Hz.
    rng : numpy.random.Generator
        Random source.
    settle_s : float
        Time generated first and dropped, s, so the record starts stationary.

    Returns
    -------
    numpy.ndarray
        The noise; shape (n,).
    """
    if sigma == 0 or n == 0:
        return np.zeros(n)
    b, a = signal.bilinear(num, den, fs=rate_hz)
    A, B, C, D = signal.tf2ss(b, a)
    P = linalg.solve_discrete_lyapunov(A, B @ B.T)
    var = float((C @ P @ C.T + D @ D.T)[0, 0])
    lead = int(math.ceil(settle_s * rate_hz))
    x = signal.lfilter(b, a, rng.standard_normal(n + lead))[lead:]
    return sigma / math.sqrt(var) * x


# -- the disturbances -------------------------------------------------------------------


@dataclass(kw_only=True)
class Disturbance(NamedEffect):
    """Base: a named effect with float parameters (SI); string fields choose its form."""

    key: ClassVar[str] = "kind"


@dataclass(kw_only=True)
class Wind(Disturbance):
    """Steady wind (m/s, NED: the direction the air moves towards)."""

    name: ClassVar[str] = "wind"
    north: float = 0.0
    east: float = 0.0
    down: float = 0.0


@dataclass(kw_only=True)
class Gust(Disturbance):
    """1-cosine discrete gust: peak (north, east, down) m/s, from ``start`` s.

    Rises as (1 - cos(pi t / rise)) / 2 over ``rise`` s, holds ``hold`` s, falls over
    ``fall`` s (MIL-F-8785C 3.7.5 shape; JSBSim FGWinds::CosineGustProfile). A gust of
    length d_m flown at V has rise = d_m / V.
    """

    name: ClassVar[str] = "gust"
    start: float = 0.0
    rise: float = 1.0
    hold: float = 0.0
    fall: float = 1.0
    north: float = 0.0
    east: float = 0.0
    down: float = 0.0

    def __post_init__(self) -> None:
        for f in ("rise", "fall"):
            if not getattr(self, f) > 0:
                raise ValueError(f"field {f!r}: must be > 0 s, got {getattr(self, f)}")
        if self.hold < 0:
            raise ValueError(f"field 'hold': must be >= 0 s, got {self.hold}")
        if self.start < 0:
            raise ValueError(f"field 'start': must be >= 0 s, got {self.start}")

    @property
    def end(self) -> float:
        """Time (s) at which the gust has died out."""
        return self.start + self.rise + self.hold + self.fall

    def factor(self, t: np.ndarray) -> np.ndarray:
        """Profile 0..1 on times ``t`` (s)."""
        s = np.asarray(t, float) - self.start
        out = np.zeros_like(s)
        up = (s >= 0) & (s < self.rise)
        out[up] = 0.5 * (1 - np.cos(np.pi * s[up] / self.rise))
        out[(s >= self.rise) & (s <= self.rise + self.hold)] = 1.0
        r = s - self.rise - self.hold
        dn = (r > 0) & (r < self.fall)
        out[dn] = 0.5 * (1 + np.cos(np.pi * r[dn] / self.fall))
        return out

    def velocities(self, t: np.ndarray) -> np.ndarray:
        """Gust velocity (n x 3, NED, m/s) on times ``t`` (s)."""
        return self.factor(t)[:, None] * np.array([self.north, self.east, self.down])


@dataclass(kw_only=True)
class Turbulence(Disturbance):
    """Continuous turbulence: Dryden, von Karman, or JSBSim's own (MIL-F-8785C).

    ``intensity`` light / moderate / severe (probability of exceedance 1e-2, 1e-3, 1e-5)
    sets sigma and the scale lengths from the height above ground (``mil_f_8785c``);
    ``sigma`` (m/s, all axes), ``sigma_u``/``sigma_v``/``sigma_w`` override it, and
    ``scale_length`` (all axes) / ``scale_length_w`` (m) the scale lengths. Components are
    along the trimmed heading (u), to its right (v) and down (w): a frozen field swept at
    the trim airspeed (Taylor). ``model = "jsbsim"`` takes only ``intensity``. Sigma 0
    with a scale length (and no intensity) is calm air: the effect at zero magnitude.
    """

    name: ClassVar[str] = "turbulence"
    model: str = "dryden"
    intensity: str = ""
    sigma: float = 0.0
    sigma_u: float = 0.0
    sigma_v: float = 0.0
    sigma_w: float = 0.0
    scale_length: float = 0.0
    scale_length_w: float = 0.0

    def __post_init__(self) -> None:
        if self.model not in TURBULENCE_MODELS:
            raise ValueError(f"field 'model': {self.model!r} is not one of "
                             f"{', '.join(TURBULENCE_MODELS)}")
        if self.intensity and self.intensity not in INTENSITIES:
            raise ValueError(f"field 'intensity': {self.intensity!r} is not one of "
                             f"{', '.join(INTENSITIES)}")
        for f in ("sigma", "sigma_u", "sigma_v", "sigma_w", "scale_length", "scale_length_w"):
            if getattr(self, f) < 0:
                raise ValueError(f"field {f!r}: must be >= 0, got {getattr(self, f)}")
        sigmas = (self.sigma, self.sigma_u, self.sigma_v, self.sigma_w)
        if not self.intensity and not any(sigmas) and not self.scale_length:
            raise ValueError("field 'intensity': give an intensity (light, moderate, severe) "
                             "or a sigma")
        if self.model == "jsbsim":
            if not self.intensity:
                raise ValueError("field 'intensity': model 'jsbsim' needs an intensity")
            if any(sigmas) or self.scale_length or self.scale_length_w:
                raise ValueError("field 'model': JSBSim's own model takes only an intensity; "
                                 "use model = 'dryden' for sigma or scale lengths")
        elif not self.intensity:
            missing = [a for a, s in zip("uvw", sigmas[1:], strict=True) if not (s or self.sigma)]
            if not (self.scale_length):
                raise ValueError("field 'scale_length': without an intensity give the scale "
                                 "length (m)")
            if missing and any(sigmas):  # all sigmas 0 with a scale length: calm air
                raise ValueError(f"field 'sigma': no sigma for axis {', '.join(missing)}")

    def intensities(self, h_agl_m: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """((sigma_u, sigma_v, sigma_w) m/s, (L_u, L_v, L_w) m) at height h_agl_m (m)."""
        if self.intensity:
            sig, L = mil_f_8785c(self.intensity, h_agl_m, self.model)
        else:
            sig, L = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        sig = tuple(s_axis or self.sigma or s for s_axis, s in
                    zip((self.sigma_u, self.sigma_v, self.sigma_w), sig, strict=True))
        lu = self.scale_length or L[0]
        lw = self.scale_length_w or self.scale_length or L[2]
        return sig, (lu, lu, lw)

    def velocities(self, n: int, rate_hz: float, speed_m_s: float, h_agl_m: float,
                   rng: np.random.Generator) -> np.ndarray:
        """Turbulence (n x 3: u along the heading, v right, w down; m/s) at rate_hz."""
        if self.model == "jsbsim":
            return np.zeros((n, 3))
        sig, L = self.intensities(h_agl_m)
        out = np.empty((n, 3))
        for i, axis in enumerate("uvw"):
            num, den = _shape(self.model, axis, L[i], speed_m_s)
            out[:, i] = filtered_noise(num, den, sig[i], n, rate_hz, rng,
                                       settle_s=10.0 * L[i] / speed_m_s)
        return out
