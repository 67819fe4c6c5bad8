"""Multisine amplitudes under a peak-deflection limit at a fixed input energy
(``limit_peak`` on an ``input_optimization.optimize_multisine`` design).

With its frequencies and phases fixed, a multisine is linear in its signed amplitudes c:
on times t_j over one period, surface s moves u_s(t_j) = (B c)_j with
B_jk = cos(2 pi f_k t_j + phi_k) for the components k on s (0 for the others). The limit
|u_s(t)| <= L on every surface is then the linear inequalities -L' <= B c <= L' on the
grid, and the energy the equality c^T G c = E (G the components' Gram matrix, rad^2 s
per unit amplitude^2); both are solved by sequential quadratic programming (SLSQP;
Kraft 1988, "A software package for sequential quadratic programming", DFVLR-FB 88-28).
Between the grid points the signal may rise above its largest grid value, but by
Bernstein's inequality for a trigonometric polynomial of highest frequency f_max,
max|u''| <= (2 pi f_max)^2 max|u| (Zygmund 1959, Trigonometric Series, Cambridge), and
u' = 0 at the maximum, so the nearest grid point (at most dt/2 away) is within
max|u| (pi f_max dt)^2 / 2 of it: the grid limit L' = L (1 - (pi f_max dt)^2 / 2)
keeps the continuous peak at or below L.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import minimize

from flightid.scenarios.input_information import Problem, covariance
from flightid.scenarios.input_optimization import (
    OptimizedMultisine,
    amplitude_cost,
    component_forms,
    criterion_value,
)
from flightid.scenarios.multisine import (
    Components,
    optimize_phases,
    period_grid,
    relative_peak_factor,
    start_at_zero,
)

Cost = Callable[[np.ndarray], tuple[float, np.ndarray]]


class PeakLimitError(ValueError):
    """No multisine found at the energy keeps every surface within the limit: the
    ``limit`` (rad), the smallest ``peak`` found at that ``energy`` (rad, rad^2 s) and
    the largest energy that design fits under the limit (``fits``, rad^2 s)."""

    def __init__(self, limit: float, peak: float, energy: float, fits: float) -> None:
        self.limit, self.peak, self.energy, self.fits = limit, peak, energy, fits
        super().__init__(
            f"no multisine at {energy:.5f} rad^2 s keeps every surface within "
            f"{np.rad2deg(limit):.2f} deg: the smallest peak found at that energy is "
            f"{np.rad2deg(peak):.2f} deg; at most {fits:.5f} rad^2 s fits under the limit")


def peak_grid(freqs: np.ndarray, period: float) -> tuple[np.ndarray, float]:
    """Times (s) over one ``period`` (s) at 64 per cycle of the highest of ``freqs`` (Hz)
    (``multisine.period_grid``) and the factor 1 - (pi f_max dt)^2 / 2 that a limit on
    the grid needs to bound the continuous peak (Bernstein's inequality).

    Parameters
    ----------
    freqs : numpy.ndarray
        The multisine's frequencies, Hz.
    period : float
        Its period, s.

    Returns
    -------
    tuple[numpy.ndarray, float]
        The times (s) and the factor.
    """
    t = period_grid(np.asarray(freqs, float), period, 64)
    dt = t[1] - t[0]
    return t, 1.0 - 0.5 * (math.pi * float(np.max(freqs)) * dt) ** 2


def peak_rows(comps: Sequence[tuple[str, float, float]], t: np.ndarray) -> np.ndarray:
    """B (surfaces, len(t), components): the unit components (surface, Hz, phase in rad)
    on times ``t`` (s), surfaces in the order they first appear.

    Parameters
    ----------
    comps : Sequence[tuple[str, float, float]]
        Unit components (surface, Hz, phase in rad).
    t : numpy.ndarray
        Times, s.

    Returns
    -------
    numpy.ndarray
        B, shape (surfaces, len(t), len(comps)).
    """
    surfaces = list(dict.fromkeys(s for s, _, _ in comps))
    rows = np.zeros((len(surfaces), t.size, len(comps)))
    for k, (s, f, ph) in enumerate(comps):
        rows[surfaces.index(s), :, k] = np.cos(2 * np.pi * f * t + ph)
    return rows


def _equalities(rows: np.ndarray, gram: np.ndarray, energy: float) -> list[dict]:
    """For variables z = (c, ...): the energy c^T gram c = ``energy`` and every surface
    at 0 at the period's start (``rows`` (surfaces, times, components) from t = 0), so
    that the input starts without a step."""
    n = rows.shape[2]
    g = gram / energy
    first = rows[:, 0, :] / math.sqrt(energy)

    def pad(m: np.ndarray, z: np.ndarray) -> np.ndarray:
        return np.hstack([m, np.zeros((m.shape[0], z.size - n))])

    return [{"type": "eq", "fun": lambda z: np.array([z[:n] @ g @ z[:n] - 1.0]),
             "jac": lambda z: pad((2 * g @ z[:n])[None], z)},
            {"type": "eq", "fun": lambda z: first @ z[:n], "jac": lambda z: pad(first, z)}]


def smallest_peak(rows: np.ndarray, gram: np.ndarray, energy: float, start: np.ndarray
                  ) -> tuple[np.ndarray, float]:
    """The signed amplitudes (rad) at input energy ``energy`` (rad^2 s), every surface
    starting at 0, that minimise the largest |u| on the grid of ``rows`` (``peak_rows``)
    from ``start``, and that peak (rad; SLSQP on (c, peak)).

    Parameters
    ----------
    rows : numpy.ndarray
        B (``peak_rows``) on a grid from t = 0.
    gram : numpy.ndarray
        Energy Gram matrix of the components, s.
    energy : float
        Input energy, rad^2 s.
    start : numpy.ndarray
        Starting amplitudes, rad.

    Returns
    -------
    tuple[numpy.ndarray, float]
        The amplitudes (rad) and the largest |u| on the grid (rad).
    """
    b = rows.reshape(-1, rows.shape[2])
    n = start.size
    c0 = start * math.sqrt(energy / float(start @ gram @ start))
    z0 = np.concatenate([c0, [np.abs(b @ c0).max()]])
    ones = np.ones((b.shape[0], 1))
    cons = [*_equalities(rows, gram, energy),
            {"type": "ineq", "fun": lambda z: np.concatenate([z[n] - b @ z[:n],
                                                               z[n] + b @ z[:n]]),
             "jac": lambda z: np.vstack([np.hstack([-b, ones]), np.hstack([b, ones])])}]
    res = minimize(lambda z: (z[n] / z0[n], np.eye(n + 1)[n] / z0[n]), z0, jac=True,
                   method="SLSQP", constraints=cons, options={"maxiter": 300, "ftol": 1e-10})
    c = res.x[:n] * math.sqrt(energy / float(res.x[:n] @ gram @ res.x[:n]))
    return c, float(np.abs(b @ c).max())


def limited_amplitudes(cost: Cost, rows: np.ndarray, gram: np.ndarray, energy: float,
                       limit: float, starts: Sequence[np.ndarray]) -> np.ndarray | None:
    """Signed amplitudes (rad) minimising ``cost`` (value and gradient of c) at input
    energy ``energy`` (rad^2 s), every surface starting at 0, with |u| <= ``limit`` (rad)
    on the grid of ``rows`` (``peak_rows``): the best of SLSQP from each of ``starts``;
    None if none converges to a point within the limit.

    Parameters
    ----------
    cost : Callable
        c -> (criterion value, gradient), e.g. ``amplitude_cost``.
    rows : numpy.ndarray
        B (``peak_rows``) on a grid from t = 0.
    gram : numpy.ndarray
        Energy Gram matrix of the components, s.
    energy : float
        Input energy, rad^2 s.
    limit : float
        Limit of |u| on the grid, rad.
    starts : Sequence[numpy.ndarray]
        Starting amplitudes, rad.

    Returns
    -------
    numpy.ndarray or None
        The amplitudes, rad.
    """
    b = rows.reshape(-1, rows.shape[2])
    inner = limit * (1 - 1e-6)  # room for SLSQP's tolerance and the energy's rescaling
    cons = [*_equalities(rows, gram, energy),
            {"type": "ineq", "fun": lambda c: np.concatenate([inner - b @ c, inner + b @ c]),
             "jac": lambda c: np.vstack([-b, b])}]
    best, best_value = None, math.inf
    for s in starts:
        c0 = s * math.sqrt(energy / float(s @ gram @ s))
        norm = max(abs(cost(c0)[0]), 1e-300)
        res = minimize(lambda c, norm=norm: tuple(v / norm for v in cost(c)), c0, jac=True,
                       method="SLSQP", constraints=cons,
                       options={"maxiter": 300, "ftol": 1e-10})
        c = res.x * math.sqrt(energy / float(res.x @ gram @ res.x))
        value = cost(c)[0]
        if np.abs(b @ c).max() <= limit and value < best_value:
            best, best_value = c, value
    return best


def _signed(comps: list[tuple[str, float, float]], amps: np.ndarray
            ) -> dict[str, Components]:
    """Per surface the components of signed amplitudes ``amps`` (a sign as a phase)."""
    out = {}
    for s in dict.fromkeys(c[0] for c in comps):
        mine = [i for i, c in enumerate(comps) if c[0] == s]
        out[s] = Components(np.array([comps[i][1] for i in mine]), np.abs(amps[mine]),
                            np.mod(np.array([comps[i][2] for i in mine])
                                   + np.where(amps[mine] < 0, np.pi, 0.0), 2 * np.pi))
    return out


def limit_peak(problem: Problem, result: OptimizedMultisine, energy: float, limit: float,
               duration: float) -> OptimizedMultisine:
    """``result`` (``optimize_multisine`` at input energy ``energy``, rad^2 s, flown in a
    flight of ``duration`` s) if no surface's peak over the period exceeds ``limit``
    (rad): unchanged, bit for bit. Else its amplitudes optimised for its criterion at the
    same energy with every surface's peak at or below the limit and a start at zero
    (``limited_amplitudes``), first with its phases, then with each surface's phases
    optimised for the new amplitudes (``optimize_phases``): the better design of the
    two. Raises ``PeakLimitError`` if neither round finds a design within the limit.

    Parameters
    ----------
    problem : Problem
        The design problem.
    result : OptimizedMultisine
        The unconstrained design.
    energy : float
        Its input energy, rad^2 s.
    limit : float
        Peak limit on every surface, rad.
    duration : float
        Flight time, s.

    Returns
    -------
    OptimizedMultisine
        ``result`` or the peak-limited design.
    """
    freqs = np.concatenate([c.freqs for c in result.components.values()])
    grid, factor = peak_grid(freqs, result.period)
    bound = limit * factor
    if max(np.abs(c(grid)).max() for c in result.components.values()) <= bound:
        return result
    shaped, best, smallest = result.components, None, math.inf
    for _ in range(2):
        comps = [(s, float(f), float(p)) for s, c in shaped.items()
                 for f, p in zip(c.freqs, c.phases, strict=True)]
        own = np.concatenate([c.amps for c in shaped.values()])
        info, middle, gram = component_forms(problem, comps, result.period, result.start,
                                          duration)
        rows = peak_rows(comps, grid)
        low, low_peak = smallest_peak(rows, gram, energy, own)
        smallest = min(smallest, low_peak)
        amps = (limited_amplitudes(amplitude_cost(problem, info, middle, result.criterion),
                                   rows, gram, energy, bound, [own, low])
                if low_peak <= bound else None)
        shaped = _signed(comps, low if amps is None else amps)
        if amps is not None:
            d = OptimizedMultisine(shaped, result.period, result.start, result.criterion,
                                   math.nan, {s: relative_peak_factor(c(grid))
                                              for s, c in shaped.items()})
            d.value = criterion_value(problem, covariance(problem, d.design(), duration),
                                      result.criterion)
            best = d if best is None or d.value < best.value else best
        shaped = {s: start_at_zero(optimize_phases(c, result.period)
                                   if c.freqs.size > 1 else c, result.period)
                  for s, c in shaped.items()}
    if best is None:
        raise PeakLimitError(limit, smallest / factor, energy,
                             energy * (bound / smallest) ** 2)
    return best
