"""Multisine inputs: Schroeder phases and orthogonal phase-optimised multisines.

A multisine is a sum of harmonics k / T (Hz) of a base period T (s). Schroeder (1970)
phases give a low peak factor for one input. For several surfaces at once, Morelli's
method (Morelli 2003, "Multiple input design for real-time parameter estimation in the
frequency domain"; Morelli & Klein 2016, 9.5) gives each input its own interleaved subset
of the harmonics, so the inputs are mutually orthogonal over the period, and optimises
the phases of each for minimum relative peak factor RPF = (max - min) / (2 sqrt(2) rms),
which is 1 for a single sinusoid. Each input is finally shifted in time so that it
starts (and, after whole periods, ends) at zero.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.optimize import minimize

from flightid.scenarios.input_design import (
    EDGE_TOL,
    InputDesign,
    SingleInput,
    check_surface,
    check_time,
    require,
)


@dataclass(frozen=True)
class Components:
    """Harmonic components of one multisine: frequency (Hz), amplitude, phase (rad)."""

    freqs: np.ndarray
    amps: np.ndarray
    phases: np.ndarray

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """sum_k a_k cos(2 pi f_k t + phi_k) at times ``t`` (s)."""
        t = np.asarray(t, float)
        out = np.zeros_like(t)
        for f, a, p in zip(self.freqs, self.amps, self.phases, strict=True):
            out += a * np.cos(2 * np.pi * f * t + p)
        return out


def harmonic_indices(f_min: float, f_max: float, period: float) -> np.ndarray:
    """Harmonic numbers k with f_min <= k / period <= f_max (Hz, s).

    Parameters
    ----------
    f_min, f_max : float
        Frequency band, Hz.
    period : float
        Fundamental period, s.

    Returns
    -------
    numpy.ndarray
        Harmonic numbers k (int), ascending.
    """
    k0 = max(1, int(np.ceil(f_min * period - 1e-9)))
    k1 = int(np.floor(f_max * period + 1e-9))
    return np.arange(k0, k1 + 1)


def split_harmonics(k: np.ndarray, n_inputs: int) -> list[np.ndarray]:
    """Interleave harmonics between inputs: input j gets k[j], k[j + n], ... (Morelli 2003).

    Parameters
    ----------
    k : numpy.ndarray
        Harmonic numbers.
    n_inputs : int
        Number of inputs sharing them.

    Returns
    -------
    list[numpy.ndarray]
        Harmonic numbers of each input; length ``n_inputs``.
    """
    return [np.asarray(k[j::n_inputs]) for j in range(n_inputs)]


def schroeder_phases(amps: np.ndarray) -> np.ndarray:
    """Schroeder (1970) phases for component amplitudes ``amps`` (rad).

    phi_k = -2 pi sum_{i<k} (k - i) p_i with p_i the relative power a_i^2 / sum a^2;
    for a flat spectrum this is phi_k = -pi k^2 / M up to a linear term.

    Parameters
    ----------
    amps : numpy.ndarray
        Component amplitudes; shape (M,).

    Returns
    -------
    numpy.ndarray
        Phases, rad; shape (M,).
    """
    p = np.asarray(amps, float) ** 2
    p = p / p.sum()
    n = p.size
    k = np.arange(1, n + 1)
    return np.array([-2 * np.pi * np.sum((kk - k[: kk - 1]) * p[: kk - 1]) for kk in k])


def relative_peak_factor(u: np.ndarray) -> float:
    """RPF = (max u - min u) / (2 sqrt(2) rms(u)); 1 for a sinusoid (Morelli 2003, eq. 9).

    Parameters
    ----------
    u : numpy.ndarray
        Signal samples over a period; not all zero.

    Returns
    -------
    float
        Relative peak factor, 1.
    """
    u = np.asarray(u, float)
    rms = np.sqrt(np.mean(u**2))
    if rms == 0:
        raise ValueError("relative peak factor of a zero signal")
    return float((u.max() - u.min()) / (2 * np.sqrt(2) * rms))


def period_grid(freqs: np.ndarray, period: float, per_cycle: int = 16) -> np.ndarray:
    """Equally spaced times (s) over one ``period`` (s): ``per_cycle`` per cycle of the
    highest of ``freqs`` (Hz), at least 1024.

    Parameters
    ----------
    freqs : numpy.ndarray
        The multisine's frequencies (Hz).
    period : float
        Its period (s).
    per_cycle : int
        Samples per cycle of the highest frequency.

    Returns
    -------
    numpy.ndarray
        Times from 0 (included) to ``period`` (excluded), s.
    """
    n = max(1024, int(per_cycle * freqs.max() * period))
    return np.arange(n) * (period / n)


def optimize_phases(comp: Components, period: float) -> Components:
    """Phases minimising the peak factor over one period, starting from ``comp``'s.

    Minimises the L_p norm of u relative to its (phase-independent) rms with analytic
    gradients for p = 4, 8, ..., 256 (the L_p route to the min-max problem, Guillaume et
    al. 1991), keeping the phases with the lowest true RPF.

    Parameters
    ----------
    comp : Components
        Starting components (frequencies, Hz; amplitudes; phases, rad).
    period : float
        Fundamental period, s.

    Returns
    -------
    Components
        The same frequencies and amplitudes with the optimised phases, rad.
    """
    t = period_grid(comp.freqs, period)
    theta = 2 * np.pi * np.outer(comp.freqs, t)
    a = comp.amps[:, None]

    def signal(ph: np.ndarray) -> np.ndarray:
        return np.sum(a * np.cos(theta + ph[:, None]), axis=0)

    best = comp.phases.copy()
    best_rpf = relative_peak_factor(signal(best))
    ph = best.copy()
    scale = np.sqrt(np.sum(comp.amps**2) / 2)
    for p in (4, 8, 16, 32, 64, 128, 256):

        def cost(x: np.ndarray, p: int = p) -> tuple[float, np.ndarray]:
            u = np.sum(a * np.cos(theta + x[:, None]), axis=0) / scale
            au = np.abs(u)
            m = au.max()
            w = (au / m) ** p
            mean_w = w.mean()
            value = np.log(m) + np.log(mean_w) / p
            # d/dx_k of log(mean |u|^p)/p = mean(|u|^(p-1) sign(u) du/dx_k) / mean(|u|^p)
            du = -(a * np.sin(theta + x[:, None])) / scale
            grad = (du @ (w / au.clip(1e-300) * np.sign(u))) / (w.sum())
            return float(value), grad

        res = minimize(cost, ph, jac=True, method="L-BFGS-B", options={"maxiter": 200})
        ph = res.x
        rpf = relative_peak_factor(signal(ph))
        if rpf < best_rpf:
            best, best_rpf = ph.copy(), rpf
    return Components(comp.freqs, comp.amps, np.mod(best, 2 * np.pi))


def start_at_zero(comp: Components, period: float) -> Components:
    """Shift a periodic multisine in time so it starts at a zero crossing (Morelli 2003).

    Of the upward zero crossings, the one with the smallest slope is taken, so the
    input starts gently; the shift changes neither the spectrum nor the peak factor.

    Parameters
    ----------
    comp : Components
        The multisine's components.
    period : float
        Fundamental period, s.

    Returns
    -------
    Components
        Components with shifted phases, rad; ``comp`` itself if there is no upward crossing.
    """
    t = period_grid(comp.freqs, period, 64)
    u = comp(t)
    up = np.nonzero((u[:-1] <= 0) & (u[1:] > 0))[0]
    if up.size == 0:
        return comp
    slope = u[up + 1] - u[up]
    i = up[np.argmin(slope)]
    t0 = t[i] + (t[i + 1] - t[i]) * (-u[i]) / (u[i + 1] - u[i])
    return Components(comp.freqs, comp.amps, comp.phases + 2 * np.pi * comp.freqs * t0)


def design_components(k: np.ndarray, period: float, peak: float, optimized: bool) -> Components:
    """Flat-spectrum multisine on harmonics ``k`` of ``period`` scaled to ``peak`` amplitude.

    Parameters
    ----------
    k : numpy.ndarray
        Harmonic numbers.
    period : float
        Fundamental period, s.
    peak : float
        Peak amplitude of the sum, rad (or the input's unit).
    optimized : bool
        True optimises the phases for a low peak factor (:func:`optimize_phases`); False
        keeps Schroeder phases.

    Returns
    -------
    Components
        Frequencies, Hz; amplitudes; phases, rad.
    """
    freqs = np.asarray(k, float) / period
    amps = np.ones(freqs.size)
    comp = Components(freqs, amps, schroeder_phases(amps))
    if optimized and freqs.size > 1:
        comp = optimize_phases(comp, period)
    comp = start_at_zero(comp, period)
    u = comp(period_grid(freqs, period, 64))
    return Components(freqs, amps * peak / np.abs(u).max(), comp.phases)


def _window(t: np.ndarray, start: float, period: float, cycles: int) -> np.ndarray:
    return (t >= start - EDGE_TOL) & (t < start + cycles * period - EDGE_TOL)


@dataclass(kw_only=True)
class Multisine(SingleInput):
    """Flat-spectrum multisine on one surface, harmonics of 1/``period`` in [f_min, f_max] Hz.

    ``amplitude`` is the peak; ``phases`` is "schroeder" or "optimized" (minimum RPF);
    repeated for ``cycles`` whole periods, zero before ``start`` and after.
    """

    kind: ClassVar[str] = "multisine"
    f_min: float = 0.1
    f_max: float = 2.0
    period: float = 20.0
    cycles: int = 1
    phases: str = "optimized"
    components: Components | None = dataclasses.field(
        default=None, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_band(self.f_min, self.f_max, self.period, self.cycles)
        require(
            self.phases in ("schroeder", "optimized"),
            "phases",
            f"'schroeder' or 'optimized', got {self.phases!r}",
        )
        k = harmonic_indices(self.f_min, self.f_max, self.period)
        self.components = design_components(
            k, self.period, self.amplitude, self.phases == "optimized"
        )

    @property
    def end(self) -> float:
        return self.start + self.cycles * self.period

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        on = _window(t, self.start, self.period, self.cycles)
        return {self.surface: np.where(on, self.components(t - self.start), 0.0)}


def _check_band(f_min: float, f_max: float, period: float, cycles: int, n: int = 1) -> None:
    require(period > 0, "period", f"must be > 0 s, got {period}")
    require(f_min > 0, "f_min", f"must be > 0 Hz, got {f_min}")
    require(f_max > f_min, "f_max", f"must exceed f_min = {f_min} Hz, got {f_max}")
    require(cycles >= 1, "cycles", f"must be >= 1, got {cycles}")
    k = harmonic_indices(f_min, f_max, period)
    require(
        k.size >= n,
        "period",
        f"only {k.size} harmonics of 1/{period} s lie in [{f_min}, {f_max}] Hz, need at "
        f"least {n}; lengthen the period or widen the band",
    )


@dataclass(kw_only=True)
class OrthogonalMultisine(InputDesign):
    """Mutually orthogonal phase-optimised multisines on several surfaces (Morelli 2003).

    The harmonics of 1/``period`` in [f_min, f_max] Hz are interleaved between the
    ``surfaces``; ``amplitudes`` are the peaks per surface (rad or fraction), or one
    ``amplitude`` for all.
    """

    kind: ClassVar[str] = "orthogonal_multisine"
    surfaces_: tuple[str, ...] = dataclasses.field(default=("de",), metadata={"alias": "surfaces"})
    amplitude: float = dataclasses.field(default=0.0, metadata={"unit": "rad"})
    amplitudes: tuple[float, ...] = dataclasses.field(default=(), metadata={"unit": "rad"})
    f_min: float = 0.1
    f_max: float = 2.0
    period: float = 20.0
    cycles: int = 1
    phases: str = "optimized"
    components: dict[str, Components] = dataclasses.field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        require(len(self.surfaces_) >= 1, "surfaces", "needs at least one surface")
        require(
            len(set(self.surfaces_)) == len(self.surfaces_),
            "surfaces",
            f"repeated surface in {self.surfaces_}",
        )
        for i, s in enumerate(self.surfaces_):
            check_surface(s, f"surfaces[{i}]")
        if self.amplitudes:
            require(
                len(self.amplitudes) == len(self.surfaces_),
                "amplitudes",
                f"{len(self.amplitudes)} amplitudes for {len(self.surfaces_)} surfaces",
            )
        require(
            self.phases in ("schroeder", "optimized"),
            "phases",
            f"'schroeder' or 'optimized', got {self.phases!r}",
        )
        _check_band(self.f_min, self.f_max, self.period, self.cycles, len(self.surfaces_))
        peaks = self.amplitudes or (self.amplitude,) * len(self.surfaces_)
        k_all = harmonic_indices(self.f_min, self.f_max, self.period)
        self.components = {
            s: design_components(k, self.period, peak, self.phases == "optimized")
            for s, k, peak in zip(
                self.surfaces_, split_harmonics(k_all, len(self.surfaces_)), peaks, strict=True
            )
        }

    def surfaces(self) -> tuple[str, ...]:
        return self.surfaces_

    @property
    def end(self) -> float:
        return self.start + self.cycles * self.period

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        on = _window(t, self.start, self.period, self.cycles)
        return {s: np.where(on, c(t - self.start), 0.0) for s, c in self.components.items()}


@dataclass(kw_only=True)
class Harmonics(InputDesign):
    """A multisine given component by component on one surface: the sum of
    ``amplitudes[k] cos(2 pi frequencies[k] (t - start) + phases[k])`` (rad or fraction,
    Hz, rad) for ``cycles`` periods of ``period`` s from ``start``, zero outside. The form
    ``flightid design-optimize`` writes its optimised spectra in (Morelli & Klein 2016,
    9.5); with harmonics of 1/``period`` and phases that start the sum at zero it also
    ends at zero."""

    kind: ClassVar[str] = "harmonics"
    surface: str = "da"
    frequencies: tuple[float, ...] = ()
    amplitudes: tuple[float, ...] = dataclasses.field(default=(), metadata={"unit": "rad"})
    phases: tuple[float, ...] = ()
    period: float = 10.0
    cycles: int = 1

    def __post_init__(self) -> None:
        check_surface(self.surface, "surface")
        n = len(self.frequencies)
        require(n >= 1, "frequencies", "needs at least one frequency (Hz)")
        require(len(self.amplitudes) == n, "amplitudes",
                f"{len(self.amplitudes)} amplitudes for {n} frequencies")
        require(len(self.phases) == n, "phases", f"{len(self.phases)} phases for {n} "
                "frequencies")
        require(all(f > 0 for f in self.frequencies), "frequencies", "must be > 0 Hz")
        require(self.period > 0, "period", f"must be > 0 s, got {self.period}")
        require(self.cycles >= 1, "cycles", f"must be >= 1, got {self.cycles}")

    def surfaces(self) -> tuple[str, ...]:
        return (self.surface,)

    @property
    def components(self) -> Components:
        """The components as arrays (Hz, rad or fraction, rad)."""
        return Components(np.asarray(self.frequencies, float),
                          np.asarray(self.amplitudes, float), np.asarray(self.phases, float))

    @property
    def end(self) -> float:
        return self.start + self.cycles * self.period

    def shapes(self, t: np.ndarray) -> dict[str, np.ndarray]:
        t = check_time(t)
        on = _window(t, self.start, self.period, self.cycles)
        return {self.surface: np.where(on, self.components(t - self.start), 0.0)}
