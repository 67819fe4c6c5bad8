"""Optimal input design: multisine spectra optimised for the predicted Cramer-Rao bounds
of ``input_information`` (Mehra 1974; Morelli 2003; Morelli & Klein 2016, ch. 9).

A multisine of whole harmonics of 1/T over whole periods is orthogonal across harmonics,
so in steady state its information is linear in the energy put on each harmonic:
M = rate * sum_k E_k Re(G_k^H R^-1 G_k), G_k the sensitivity of the frequency response
to the parameters at harmonic k on one surface (Mehra 1974, "Optimal input signals for
parameter estimation in dynamic systems - survey and new results", IEEE TAC 19(6);
Morelli & Klein 2016, 9.4). The energies are optimised for a D-optimal (largest
log det M) or a relative A-optimal criterion (smallest sum of variance / truth^2) at a
fixed total energy; each harmonic goes to one surface (orthogonal inputs, Morelli 2003),
and the phases of each surface's components are then optimised for the smallest relative
peak factor (``multisine.optimize_phases``). Designs are compared on the time-domain
information of the whole flight (trim, input, free response), which includes transients.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from flightid.scenarios.input_information import (
    Problem,
    _forms,
    _inputs,
    _propagate,
    covariance,
)
from flightid.scenarios.inputs import Maneuvers
from flightid.scenarios.multisine import (
    Components,
    Harmonics,
    harmonic_indices,
    optimize_phases,
    relative_peak_factor,
    schroeder_phases,
    start_at_zero,
)

CRITERIA = ("A", "D", "mean")


# -- optimisation of the multisine ------------------------------------------------------


def criterion_value(problem: Problem, cov: np.ndarray, criterion: str = "A") -> float:
    """'A': sum over the problem's derivatives of variance / truth^2 (relative A-optimal;
    those with truth 0 do not count); 'D': log det of their covariance (D-optimal);
    'mean': the mean of bound / |truth| (``mean_relative_bound``).

    Parameters
    ----------
    problem : Problem
        The design problem.
    cov : numpy.ndarray
        Covariance of all model parameters; shape (P, P).
    criterion : str, optional
        ``"A"`` (default), ``"D"`` or ``"mean"``.

    Returns
    -------
    float
        The criterion's value (inf for 'D' with a singular covariance).
    """
    idx = [problem.model.parameters.index(n) for n in problem.names]
    sub = cov[np.ix_(idx, idx)]
    if criterion == "D":
        sign, logdet = np.linalg.slogdet(sub)
        return float(logdet) if sign > 0 else math.inf
    if criterion == "A":
        return float(np.sum(problem.weights() * np.diag(sub)))
    if criterion == "mean":
        rel = np.sqrt(np.clip(np.diag(sub), 0, None) * problem.weights())
        return float(np.mean(rel[problem.weights() > 0]))
    raise ValueError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")


def _criterion_weight(problem: Problem, cov: np.ndarray, criterion: str) -> np.ndarray:
    """W with d criterion = tr(W d cov) (P x P over all parameters)."""
    params = problem.model.parameters
    idx = [params.index(n) for n in problem.names]
    W = np.zeros_like(cov)
    if criterion == "D":
        W[np.ix_(idx, idx)] = np.linalg.inv(cov[np.ix_(idx, idx)])
    elif criterion == "mean":
        w = problem.weights()
        std = np.sqrt(np.clip(np.diag(cov)[idx], 1e-300, None))
        W[idx, idx] = np.sqrt(w) / (2 * std * np.count_nonzero(w))
    else:
        W[idx, idx] = problem.weights()
    return W


def amplitude_cost(problem: Problem, info: np.ndarray, middle: np.ndarray,
                   criterion: str) -> Callable[[np.ndarray], tuple[float, np.ndarray]]:
    """The criterion of the predicted covariance M^-1 V M^-1 as a function of the
    amplitudes c of K - 1 input components (component 0 the constant bias input, fixed at
    1), M = sum c_a c_b info[a, b], V = sum c_a c_b middle[a, b]: c -> (value, gradient).

    Parameters
    ----------
    problem : Problem
        The design problem.
    info : numpy.ndarray
        Information of each component pair; shape (K, K, P, P).
    middle : numpy.ndarray
        The sandwich's middle term of each component pair; shape (K, K, P, P).
    criterion : str
        ``"A"``, ``"D"`` or ``"mean"``.

    Returns
    -------
    Callable
        c (rad, shape (K - 1,)) -> (criterion value, its gradient in c).
    """

    def cost(c: np.ndarray) -> tuple[float, np.ndarray]:
        ext = np.concatenate([[1.0], c])
        M = np.einsum("a,b,abij->ij", ext, ext, info)
        V = np.einsum("a,b,abij->ij", ext, ext, middle)
        try:
            Minv = np.linalg.inv(M)
        except np.linalg.LinAlgError:
            return math.inf, np.zeros_like(c)
        cov = Minv @ V @ Minv
        value = criterion_value(problem, cov, criterion)
        W = _criterion_weight(problem, cov, criterion)
        g1 = -(cov @ W @ Minv + Minv @ W @ cov)
        g2 = Minv @ W @ Minv
        tm = np.einsum("b,kbij->kij", ext, info[1:])
        tv = np.einsum("b,kbij->kij", ext, middle[1:])
        g = (np.einsum("kij,ji->k", tm + tm.transpose(0, 2, 1), g1)
             + np.einsum("kij,ji->k", tv + tv.transpose(0, 2, 1), g2))
        return value, g

    return cost


def optimal_amplitudes(problem: Problem, info: np.ndarray, middle: np.ndarray,
                       gram: np.ndarray, energy: float, criterion: str,
                       start: np.ndarray) -> np.ndarray:
    """Amplitudes c of K input components that minimise the criterion
    (``amplitude_cost``) at input energy c^T gram c = ``energy`` (rad^2 s; gram over
    components 1..K-1): c = x sqrt(energy / x^T gram x), quasi-Newton (L-BFGS-B) on x
    with the analytic gradient from ``start``.

    Parameters
    ----------
    problem : Problem
        The design problem.
    info : numpy.ndarray
        Information of each component pair; shape (K, K, P, P).
    middle : numpy.ndarray
        The sandwich's middle term of each component pair; shape (K, K, P, P).
    gram : numpy.ndarray
        Energy Gram matrix of components 1..K-1, s; shape (K - 1, K - 1).
    energy : float
        Input energy, rad^2 s.
    criterion : str
        ``"A"``, ``"D"`` or ``"mean"``.
    start : numpy.ndarray
        Starting x; shape (K - 1,).

    Returns
    -------
    numpy.ndarray
        Amplitudes of components 1..K-1, rad; shape (K - 1,).
    """
    of_c = amplitude_cost(problem, info, middle, criterion)

    def cost(x: np.ndarray) -> tuple[float, np.ndarray]:
        q = float(x @ gram @ x)
        scale = math.sqrt(energy / q)
        value, g = of_c(x * scale)
        if not math.isfinite(value):
            return value, np.zeros_like(x)
        grad = scale * g - scale * np.dot(x, g) * (gram @ x) / q
        return value, grad

    res = minimize(cost, np.asarray(start, float), jac=True, method="L-BFGS-B",
                   options={"maxiter": 300})
    return res.x * math.sqrt(energy / float(res.x @ gram @ res.x))


@dataclass
class OptimizedMultisine:
    """An optimised multisine: per surface its components (Hz, rad, rad), the criterion
    and its value, the period (s), the start (s) and the relative peak factor per
    surface."""

    components: dict[str, Components]
    period: float
    start: float
    criterion: str
    value: float
    peak_factor: dict[str, float] = field(default_factory=dict)

    def design(self) -> Maneuvers:
        """The multisine as a design: one ``harmonics`` part per surface."""
        return Maneuvers(parts=tuple(
            Harmonics(surface=s, frequencies=tuple(float(f) for f in c.freqs),
                      amplitudes=tuple(float(a) for a in c.amps),
                      phases=tuple(float(p) for p in c.phases), period=self.period,
                      start=self.start)
            for s, c in self.components.items()))


def _unit_parts(comps: list[tuple[str, float, float]], period: float,
                start: float) -> list[Harmonics]:
    return [Harmonics(surface=s, frequencies=(f,), amplitudes=(1.0,), phases=(ph,),
                      period=period, start=start) for s, f, ph in comps]


def component_forms(problem: Problem, comps: list[tuple[str, float, float]], period: float,
                    start: float, duration: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The quadratic forms (info, middle: ``_forms``, the constant bias input first) and
    the Gram matrix (rad^2 s per unit amplitude^2) of unit multisine components
    (surface, Hz, phase in rad) of ``period`` (s) flown once from ``start`` (s) in a
    flight of ``duration`` (s).

    Parameters
    ----------
    problem : Problem
        The design problem.
    comps : list[tuple[str, float, float]]
        Unit components (surface, Hz, phase in rad), K - 1 of them.
    period : float
        Multisine period, s.
    start : float
        Start of the input, s.
    duration : float
        Flight time, s.

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray, numpy.ndarray]
        info and middle, shape (K, K, P, P), and gram, shape (K - 1, K - 1).
    """
    t = np.arange(int(round(duration * problem.rate)) + 1) / problem.rate
    parts = _unit_parts(comps, period, start)
    u = np.stack([np.zeros((t.size, len(problem.model.inputs) + 1))]
                 + [_inputs(problem, d, t) for d in parts])
    u[0, :, -1] = 1.0
    u[1:, :, -1] = 0.0
    info, middle = _forms(problem, _propagate(problem, u))
    flat = u[1:, :, :-1].reshape(len(parts), -1)
    return info, middle, flat @ flat.T / problem.rate


def _amplitude_round(problem: Problem, comps: list[tuple[str, float, float]],
                     period: float, start: float, duration: float, energy: float,
                     criterion: str, guess: np.ndarray | None) -> np.ndarray:
    """Optimal amplitudes of unit components (surface, Hz, phase) flown from ``start``."""
    info, middle, gram = component_forms(problem, comps, period, start, duration)
    return optimal_amplitudes(problem, info, middle, gram, energy, criterion,
                              np.ones(len(comps)) if guess is None else guess)


def optimize_multisine(problem: Problem, surfaces: Sequence[str], band: tuple[float, float],
                       period: float, energy: float, criterion: str = "A",
                       start: float = 2.0, settle: float = 8.0,
                       min_share: float = 0.02) -> OptimizedMultisine:
    """A multisine on ``surfaces`` of harmonics of 1/``period`` (s) in ``band`` (Hz), flown
    once from ``start`` (s) and followed by ``settle`` s of free response, with input energy
    ``energy`` (rad^2 s), its amplitudes optimised for ``criterion`` on the predicted
    output-error covariance of the whole flight (``covariance``, transients included).

    1. the harmonics interleaved between the surfaces (mutually orthogonal inputs, Morelli
       2003; Schroeder phases), amplitudes optimised;
    2. those under ``min_share`` of the largest amplitude dropped (each surface keeps its
       strongest), amplitudes optimised again;
    3. each surface's phases optimised for the smallest relative peak factor and shifted to
       start at zero (``multisine.optimize_phases``, ``start_at_zero``), amplitudes
       optimised once more with those phases (and the start shifted to a zero again).
    The criterion's value is that of the final design; ``peak_limit.limit_peak`` holds
    its peak under a limit.

    Parameters
    ----------
    problem : Problem
        The design problem.
    surfaces : Sequence[str]
        Surfaces the multisine moves.
    band : tuple[float, float]
        Frequency band (low, high), Hz.
    period : float
        Multisine period, s.
    energy : float
        Input energy, rad^2 s.
    criterion : str, optional
        ``"A"`` (default), ``"D"`` or ``"mean"``.
    start : float, optional
        Start of the input, s. Default 2.
    settle : float, optional
        Free response after the input, s. Default 8.
    min_share : float, optional
        Smallest amplitude kept, as a share of the largest. Default 0.02.

    Returns
    -------
    OptimizedMultisine
        Components per surface, criterion value, period, start and peak factors.
    """
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")
    k = harmonic_indices(band[0], band[1], period)
    if k.size < 1:
        raise ValueError(f"no harmonic of 1/{period:g} s lies in [{band[0]:g}, {band[1]:g}] "
                         "Hz; widen the band or lengthen the input")
    freqs = k / period
    duration = start + period + settle
    flat = schroeder_phases(np.ones(freqs.size))
    comps = [(surfaces[i % len(surfaces)], freqs[i], flat[i]) for i in range(freqs.size)]
    amps = _amplitude_round(problem, comps, period, start, duration, energy, criterion, None)
    strongest = {max((i for i in range(freqs.size) if i % len(surfaces) == j),
                     key=lambda i: abs(amps[i])) for j in range(min(len(surfaces), freqs.size))}
    keep = [i for i in range(freqs.size)
            if abs(amps[i]) > min_share * np.abs(amps).max() or i in strongest]
    comps = [comps[i] for i in keep]
    guess = amps[keep]
    amps = _amplitude_round(problem, comps, period, start, duration, energy, criterion, guess)
    shaped: dict[str, Components] = {}
    for s in surfaces:
        mine = [i for i, c in enumerate(comps) if c[0] == s]
        if not mine:
            continue
        a = np.abs(amps[mine])
        ph = np.array([comps[i][2] for i in mine]) + np.where(amps[mine] < 0, np.pi, 0.0)
        comp = Components(np.array([comps[i][1] for i in mine]), a, ph)
        if len(mine) > 1:
            comp = optimize_phases(comp, period)
        shaped[s] = start_at_zero(comp, period)
    comps = [(s, float(f), float(p)) for s, c in shaped.items()
             for f, p in zip(c.freqs, c.phases, strict=True)]
    guess = np.concatenate([c.amps for c in shaped.values()])
    amps = _amplitude_round(problem, comps, period, start, duration, energy, criterion, guess)
    final: dict[str, Components] = {}
    for s in shaped:
        mine = [i for i, c in enumerate(comps) if c[0] == s]
        final[s] = start_at_zero(Components(
            np.array([comps[i][1] for i in mine]), np.abs(amps[mine]),
            np.mod(np.array([comps[i][2] for i in mine])
                   + np.where(amps[mine] < 0, np.pi, 0.0), 2 * np.pi)), period)
    grid = np.arange(4096) * (period / 4096)
    result = OptimizedMultisine(final, float(period), float(start), criterion, math.nan,
                                {s: relative_peak_factor(c(grid)) for s, c in final.items()})
    result.value = criterion_value(problem, covariance(problem, result.design(), duration),
                                   criterion)
    return result

