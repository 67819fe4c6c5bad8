"""The predicted Cramer-Rao bounds of an input design: the design ``Problem`` of a card's
flight without inputs, the output sensitivities of a design and the predicted covariance
of an output-error fit (Morelli & Klein 2016, eq. 6.20 and 6.54).

The prediction linearises the aircraft at the card's trim: the identification's own
linear model (``identification.linear_models``, e.g. the lateral model of Morelli & Klein
example 6.1) at the condition of a flight of the card, with the card's JSBSim truth as
parameter values and the card's sensor noise (measured minus true output, per channel)
as the measurement noise. The Fisher information of output error is
M = sum_i S_i^T R^-1 S_i, S_i the output sensitivities at sample i (Morelli & Klein 2016,
eq. 6.20); its inverse bounds the covariance of the estimates (Cramer-Rao).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
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
