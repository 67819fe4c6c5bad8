"""Optimal input design: predicted Cramer-Rao bounds of a design, and multisine spectra
optimised for them (Mehra 1974; Morelli 2003; Morelli & Klein 2016, ch. 9).

The prediction linearises the aircraft at the card's trim: the identification's own
linear model (``identification.linear_models``, e.g. the lateral model of Morelli & Klein
example 6.1) at the condition of a flight of the card, with the card's JSBSim truth as
parameter values and the card's sensor noise (measured minus true output, per channel)
as the measurement noise. The Fisher information of output error is
M = sum_i S_i^T R^-1 S_i, S_i the output sensitivities at sample i (Morelli & Klein 2016,
eq. 6.20); its inverse bounds the covariance of the estimates (Cramer-Rao).

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
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm
from scipy.optimize import minimize
from scipy.signal import welch

from flightid.identification.evaluation.scoring import record_truth
from flightid.identification.models.linear import (
    LinearModel,
    matrix_sensitivities,
    model_for_record,
)
from flightid.identification.models.structure import linear
from flightid.record import FlightRecord
from flightid.scenarios.input_design import InputDesign
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
BIAS_PREFIX = "bias_"


@dataclass(frozen=True)
class Problem:
    """What a design is optimised for: the linear ``model`` at the card's trim, the true
    parameter ``values`` (the model's units: derivatives per rad, biases 0), the
    derivatives ``names`` whose bounds count, the output sample ``rate`` (Hz) and the
    residual an output-error fit leaves without any input: its ``variance`` per model
    output (SI^2: the weights R of the fit) and its power spectral density per sample
    (``density``: SI^2, one row per frequency of ``frequencies`` in Hz, one column per
    output; the variance for white noise), from the sensors' noise and the turbulence."""

    model: LinearModel
    values: dict[str, float]
    names: tuple[str, ...]
    rate: float
    variance: dict[str, float]
    frequencies: np.ndarray
    density: np.ndarray

    def density_at(self, f: np.ndarray) -> np.ndarray:
        """The residual density (SI^2 per sample) at frequencies ``f`` (Hz), (len(f),
        outputs); held constant below and above the estimated band."""
        f = np.clip(np.abs(np.asarray(f, float)), self.frequencies[1], self.frequencies[-1])
        return np.column_stack([np.interp(f, self.frequencies, self.density[:, j])
                                for j in range(self.density.shape[1])])

    def weights(self) -> np.ndarray:
        """1 / truth^2 per name (1/rad^-2 ...), 0 where the truth is 0: the relative
        A-criterion's weights."""
        truth = np.array([self.values[n] for n in self.names])
        return np.where(truth != 0, 1.0 / np.where(truth != 0, truth, 1.0) ** 2, 0.0)


def residual_spectrum(record: FlightRecord, channels: Sequence[str], segment_s: float = 10.24
                      ) -> tuple[dict[str, float], np.ndarray, np.ndarray]:
    """The residual of a flight without inputs, per channel: (variance (SI^2), frequencies
    (Hz), density per sample (SI^2), columns in ``channels`` order). Welch's method with
    linearly detrended segments of ``segment_s`` s (Welch 1967; Ljung 1999, 6.4); the
    density per sample is rate x the one-sided density / 2, so white noise of variance
    sigma^2 has density sigma^2 at every frequency.

    Parameters
    ----------
    record : FlightRecord
        Measured flight without inputs, at least ``2 * segment_s`` long.
    channels : Sequence[str]
        Output channels.
    segment_s : float, optional
        Welch segment length, s. Default 10.24.

    Returns
    -------
    tuple[dict[str, float], numpy.ndarray, numpy.ndarray]
        (channel -> variance, SI^2; frequencies, Hz, shape (F,); density per sample, SI^2,
        shape (F, len(channels))).
    """
    rate = float(1.0 / np.median(np.diff(record.time)))
    nper = int(round(segment_s * rate))
    if record.time.size < 2 * nper:
        raise ValueError(f"the quiet flight is {record.time[-1]:.1f} s; the residual spectrum "
                         f"needs at least {2 * segment_s:.0f} s")
    cols, variance = [], {}
    freqs = np.zeros(0)
    for c in channels:
        x = np.asarray(record[c], float)
        freqs, p1 = welch(x, fs=rate, nperseg=nper, detrend="linear")
        variance[c] = float(np.sum(p1) * (freqs[1] - freqs[0]))
        if not variance[c] > 0:
            raise ValueError(f"channel {c!r} has no noise in this flight: its bound would be "
                             "0; give the card a sensor suite")
        cols.append(rate * p1 / 2.0)
    return variance, freqs, np.column_stack(cols)


def problem_from_flight(measured: FlightRecord, truth: FlightRecord, model: str = "lat",
                        derivatives: Sequence[str] | None = None) -> Problem:
    """The design problem of a flight without inputs (trim, turbulence, sensors): ``model``
    (a linear preset, 'lat' or 'lon' ...) at the measured record's condition, the truth
    the truth record carries, and the residual spectrum of the measured outputs.
    ``derivatives`` defaults to the model's.

    Parameters
    ----------
    measured : FlightRecord
        Measured flight without inputs.
    truth : FlightRecord
        Its truth record (the true derivatives).
    model : str, optional
        Linear model preset. Default ``"lat"``.
    derivatives : Sequence[str] or None, optional
        Derivatives whose bounds count; None uses the model's.

    Returns
    -------
    Problem
        The design problem.
    """
    kwargs = {"derivatives": tuple(derivatives)} if derivatives else {}
    lin = model_for_record(linear(model), measured, **kwargs)
    table = record_truth(truth)
    values = {p: float(table.get(p, lin.start[p])) if not p.startswith(BIAS_PREFIX) else 0.0
              for p in lin.parameters}
    names = tuple(p for p in lin.parameters if not p.startswith(BIAS_PREFIX))
    variance, freqs, density = residual_spectrum(measured, lin.outputs)
    return Problem(lin, values, names, float(1.0 / np.median(np.diff(measured.time))),
                   variance, freqs, density)


# -- information -----------------------------------------------------------------------


def _inputs(problem: Problem, design: InputDesign, t: np.ndarray) -> np.ndarray:
    """(N, m + 1) model inputs on ``t``: the design's increments on the model's inputs
    (zero for a surface it does not move) and the constant 1 of the bias column."""
    sig = design.signals(t)
    unknown = [s for s in sig if s not in problem.model.inputs and np.any(sig[s])]
    if unknown:
        raise ValueError(f"the design moves {', '.join(unknown)}, which the "
                         f"{problem.model.name} model has no input for "
                         f"({', '.join(problem.model.inputs)})")
    cols = [sig.get(s, np.zeros_like(t)) for s in problem.model.inputs]
    return np.column_stack([*cols, np.ones_like(t)])


def _propagate(problem: Problem, u: np.ndarray) -> np.ndarray:
    """Output sensitivities (K, N, outputs, P) to the model's P parameters (biases
    included) of K input histories ``u`` (K, N, inputs + 1; the last column the constant
    1) from zero initial perturbation at the problem's rate: states and sensitivities
    propagated exactly for inputs held over each sample (one matrix exponential of the
    augmented system)."""
    model = problem.model
    params = model.parameters
    (A, B, C, D), (dA, dB, dC, dD) = matrix_sensitivities(model, problem.values, params)
    n, m = B.shape
    p = len(params)
    size = n * (1 + p)
    big = np.zeros((size + m, size + m))
    big[:n, :n] = A
    big[:n, size:] = B
    for k in range(p):
        rows = slice(n * (k + 1), n * (k + 2))
        big[rows, rows] = A
        big[rows, :n] = dA[k]
        big[rows, size:] = dB[k]
    step = expm(big / problem.rate)
    phi, gamma = step[:size, :size].T, step[:size, size:].T
    K, N, _ = u.shape
    z = np.zeros((N, K, size))
    for i in range(1, N):
        z[i] = z[i - 1] @ phi + u[:, i - 1] @ gamma
    z = z.transpose(1, 0, 2)
    x = z[..., :n]
    sens = np.empty((K, N, C.shape[0], p))
    for k in range(p):
        sens[..., k] = z[..., n * (k + 1):n * (k + 2)] @ C.T + x @ dC[k].T + u @ dD[k].T
    return sens


def sensitivities(problem: Problem, design: InputDesign, duration: float) -> np.ndarray:
    """Output sensitivities (N, outputs, P; SI per parameter unit, P the model's
    parameters, biases included) of a flight of ``duration`` s with ``design`` from zero
    initial perturbation, sampled at the problem's rate.

    Parameters
    ----------
    problem : Problem
        The design problem.
    design : InputDesign
        The input design.
    duration : float
        Flight duration, s.

    Returns
    -------
    numpy.ndarray
        Output sensitivities; shape (N, outputs, P).
    """
    t = np.arange(int(round(duration * problem.rate)) + 1) / problem.rate
    return _propagate(problem, _inputs(problem, design, t)[None])[0]


def _forms(problem: Problem, sens: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic forms of K sensitivity histories (K, N, outputs, P): information
    Q[a, b] = sum_i S_a,i^T R^-1 S_b,i and coloured middle term
    V[a, b] = sum_f Re(S_a,f^H R^-1 Phi_f R^-1 S_b,f) / N over the DFT bins f, each
    (K, K, P, P); the sensitivities of a sum of the K inputs with amplitudes c have
    information sum c_a c_b Q[a, b] (superposition)."""
    K, N, n_out, P = sens.shape
    r = np.array([problem.variance[o] for o in problem.model.outputs])
    white = (sens / np.sqrt(r)[None, None, :, None]).transpose(1, 2, 0, 3).reshape(
        N * n_out, K * P)
    info = (white.T @ white).reshape(K, P, K, P).transpose(0, 2, 1, 3)
    spec = np.fft.rfft(sens, axis=1)
    f = np.fft.rfftfreq(N, 1.0 / problem.rate)
    weight = np.full(f.size, 2.0)
    weight[0] = 1.0
    if N % 2 == 0:
        weight[-1] = 1.0
    w = np.sqrt(weight[:, None] * problem.density_at(f) / r[None, :] ** 2 / N)
    colored = (spec * w[None, :, :, None]).transpose(1, 2, 0, 3).reshape(-1, K * P)
    middle = np.real(colored.conj().T @ colored).reshape(K, P, K, P).transpose(0, 2, 1, 3)
    return info, middle


def _sandwich(info: np.ndarray, middle: np.ndarray) -> np.ndarray:
    inv = np.linalg.pinv(info)
    return inv @ middle @ inv


def covariance(problem: Problem, design: InputDesign, duration: float) -> np.ndarray:
    """Predicted covariance (P x P) of an output-error fit of a flight of ``duration`` s
    with ``design``: weights R^-1 (the residual variances), information
    M = sum_i S_i^T R^-1 S_i (Morelli & Klein 2016, eq. 6.20) and the coloured residual's
    sandwich M^-1 (sum_f S_f^H R^-1 Phi_f R^-1 S_f / N) M^-1 over the DFT bins f of the
    sensitivities (the frequency-domain form of Morelli & Klein 2016, eq. 6.54), Phi the
    residual density; the white-noise Cramer-Rao bound M^-1 when Phi = R.

    Parameters
    ----------
    problem : Problem
        The design problem.
    design : InputDesign
        The input design.
    duration : float
        Flight duration, s.

    Returns
    -------
    numpy.ndarray
        Predicted covariance of all model parameters, their units squared; shape (P, P).
    """
    info, middle = _forms(problem, sensitivities(problem, design, duration)[None])
    return _sandwich(info[0, 0], middle[0, 0])


def bounds(problem: Problem, cov: np.ndarray) -> dict[str, float]:
    """Standard deviations (the parameters' units) of the problem's derivatives from a
    covariance over all model parameters.

    Parameters
    ----------
    problem : Problem
        The design problem.
    cov : numpy.ndarray
        Covariance of all model parameters; shape (P, P).

    Returns
    -------
    dict[str, float]
        Derivative name -> standard deviation.
    """
    params = problem.model.parameters
    diag = np.diag(cov)
    return {n: float(np.sqrt(max(diag[params.index(n)], 0.0))) for n in problem.names}


def predicted_bounds(problem: Problem, design: InputDesign, duration: float
                     ) -> dict[str, float]:
    """The predicted output-error bounds of the problem's derivatives for ``design`` flown
    for ``duration`` s (``covariance``).

    Parameters
    ----------
    problem : Problem
        The design problem.
    design : InputDesign
        The input design.
    duration : float
        Flight duration, s.

    Returns
    -------
    dict[str, float]
        Derivative name -> predicted standard deviation.
    """
    return bounds(problem, covariance(problem, design, duration))


def relative_bounds(problem: Problem, bound: Mapping[str, float]) -> dict[str, float]:
    """bound / |truth| per derivative with a non-zero truth (a fraction).

    Parameters
    ----------
    problem : Problem
        The design problem (its true values).
    bound : Mapping[str, float]
        Derivative name -> standard deviation.

    Returns
    -------
    dict[str, float]
        Derivative name -> bound / |truth|, 1.
    """
    return {n: bound[n] / abs(problem.values[n]) for n in problem.names
            if problem.values[n] != 0}


def mean_relative_bound(problem: Problem, bound: Mapping[str, float]) -> float:
    """The mean of bound / |truth| over the derivatives with a non-zero truth.

    Parameters
    ----------
    problem : Problem
        The design problem (its true values).
    bound : Mapping[str, float]
        Derivative name -> standard deviation.

    Returns
    -------
    float
        Mean bound / |truth|, 1.
    """
    rel = relative_bounds(problem, bound)
    return float(np.mean(list(rel.values())))


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

