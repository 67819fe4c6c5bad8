"""The filter-error method's model and likelihood: the steady-state Kalman filter of a
linear model with process noise (Jategaonkar 2015 ch. 5; Van Loan 1978 for the
discretised process noise), the innovations and their negative log-likelihood. One
Gauss-Newton pass with R fixed and the measurement-noise step with the F-compensation
(Jategaonkar eq. 5.41) are ``iteration``; ``relaxation`` alternates them.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from flightid.identification.methods.output_error_problem import Problem
from flightid.identification.models.discrete import (
    discretize,
    hold_inputs,
    propagate,
    stacked_product,
)
from flightid.identification.models.linear import LinearModel

# Euler angles follow from the rates by kinematics: turbulence does not enter them
PROCESS_NOISE_PREFIX = "F_"
# the measurement-noise standard deviation of an output when it is estimated jointly
MEASUREMENT_NOISE_PREFIX = "sigma_"
# relative step of the central differences of the filter matrices: truncation error
# ~1e-10, rounding of the Riccati solution (~1e-13 relative) amplified to ~1e-8
RELATIVE_STEP = 1e-5
# the Riccati solutions kept: a parameter that moves only B or D (a bias, a control
# derivative) leaves Phi, C, Q_d and R, so the finite-difference sensitivities of
# ``evaluate`` reuse the filter's P instead of solving again (most of the method's time)
RICCATI_CACHE = 8
_riccati: OrderedDict[bytes, tuple[np.ndarray, np.ndarray]] = OrderedDict()


def process_noise_name(state: str) -> str:
    """Parameter name of the process-noise standard deviation of a state equation.

    Parameters
    ----------
    state : str
        State name, e.g. 'beta'.

    Returns
    -------
    str
        'F_<state>'.
    """
    return f"{PROCESS_NOISE_PREFIX}{state}"


def measurement_noise_name(output: str) -> str:
    """Parameter name of the measurement-noise standard deviation of an output.

    Parameters
    ----------
    output : str
        Output name, e.g. 'ay'.

    Returns
    -------
    str
        'sigma_<output>'.
    """
    return f"{MEASUREMENT_NOISE_PREFIX}{output}"


def is_noise_parameter(name: str) -> bool:
    """Whether a parameter is a noise parameter (F_<state>, sigma_<output>), not the model's.

    Parameters
    ----------
    name : str
        Parameter name.

    Returns
    -------
    bool
        True for F_<state> and sigma_<output>.
    """
    return name.startswith((PROCESS_NOISE_PREFIX, MEASUREMENT_NOISE_PREFIX))


@dataclass
class SteadyStateFilter:
    """Discrete model and steady-state Kalman filter of one parameter set (SI units).

    phi, gamma: discrete state and input matrices (input w_i of ``models.discrete.hold_inputs``);
    C, D: output matrices; Qd: process-noise covariance per sample; P: predicted-state
    covariance; S: innovation covariance; K: Kalman gain.
    """

    phi: np.ndarray
    gamma: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Qd: np.ndarray
    P: np.ndarray
    S: np.ndarray
    K: np.ndarray


def process_noise_covariance(A: np.ndarray, F: np.ndarray, dt: float) -> np.ndarray:
    """Q_d = int_0^dt e^{A s} F F^T e^{A^T s} ds for xdot = A x + F n, n unit white noise.

    Van Loan (1978): the blocks of expm([[-A, F F^T], [0, A^T]] dt).

    Parameters
    ----------
    A : numpy.ndarray
        Continuous-time state matrix, shape (n, n), 1/s.
    F : numpy.ndarray
        Process-noise matrix, shape (n, n), state units per sqrt(s) (state rate per
        sqrt(Hz)).
    dt : float
        Sample interval, s.

    Returns
    -------
    numpy.ndarray
        Q_d, shape (n, n), state units squared; symmetric.
    """
    n = A.shape[0]
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n] = -A * dt
    big[:n, n:] = F @ F.T * dt
    big[n:, n:] = A.T * dt
    # a trial step of the optimiser may make A explode: the non-finite Q_d that follows is
    # rejected by the caller (``iteration``), not warned about
    with np.errstate(over="ignore", invalid="ignore"):
        e = scipy.linalg.expm(big)
        phi = e[n:, n:].T
        q = phi @ e[:n, n:]
    return 0.5 * (q + q.T)


def steady_state_filter(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                        F: np.ndarray, R: np.ndarray, dt: float,
                        hold: str = "foh") -> SteadyStateFilter:
    """Discretise (A, B) and F, solve the discrete Riccati equation, return the filter.

    Parameters
    ----------
    A : numpy.ndarray
        State matrix, shape (n, n), 1/s.
    B : numpy.ndarray
        Input matrix, shape (n, m + 1), the last column for the constant 1.
    C : numpy.ndarray
        Output matrix, shape (ny, n).
    D : numpy.ndarray
        Feed-through matrix, shape (ny, m + 1).
    F : numpy.ndarray
        Process-noise matrix, shape (n, n), state units per sqrt(s).
    R : numpy.ndarray
        Measurement-noise covariance, shape (ny, ny), output units squared.
    dt : float
        Sample interval, s.
    hold : str, optional
        Inputs between samples: 'foh' (default) or 'zoh'.

    Returns
    -------
    SteadyStateFilter
        Discrete matrices, Q_d, P, S and K.

    Raises
    ------
    numpy.linalg.LinAlgError
        The Riccati equation has no stabilising solution.
    """
    n = A.shape[0]
    phi, gamma, _, _ = discretize(A, B, dt, np.zeros((0, n, n)),
                                     np.zeros((0, *B.shape)), hold)
    qd, P = _covariances(A, C, F, R, dt, phi)
    S = C @ P @ C.T + R
    K = np.linalg.solve(S, C @ P).T  # P C^T S^-1 (S symmetric)
    return SteadyStateFilter(phi, gamma, C, D, qd, P, 0.5 * (S + S.T), K)


def _covariances(A: np.ndarray, C: np.ndarray, F: np.ndarray, R: np.ndarray, dt: float,
                 phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Q_d, P): the process-noise covariance and the Riccati solution (``RICCATI_CACHE``)."""
    key = b"".join(np.ascontiguousarray(m, dtype=float).tobytes() for m in (A, C, F, R)) \
        + np.float64(dt).tobytes() + np.array(C.shape).tobytes()
    if key in _riccati:
        _riccati.move_to_end(key)
        return _riccati[key]
    qd = process_noise_covariance(A, F, dt)
    if np.any(qd):
        # solve_discrete_are(a, b, q, r) is the control form; the filter's predicted
        # covariance is its dual with a = Phi^T, b = C^T
        P = scipy.linalg.solve_discrete_are(phi.T, C.T, qd, R)
        P = 0.5 * (P + P.T)
    else:
        P = np.zeros((A.shape[0], A.shape[0]))
    _riccati[key] = (qd, P)
    if len(_riccati) > RICCATI_CACHE:
        _riccati.popitem(last=False)
    return qd, P


def innovations(flt: SteadyStateFilter, u: np.ndarray, w: np.ndarray, z: np.ndarray,
                x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Predicted states x~ and innovations nu of the steady-state filter.

    The predictor is LTI: x~_{k+1} = Phi (I - K C) x~_k + Phi K (z_k - D u_k) + Gamma w_k.

    Parameters
    ----------
    flt : SteadyStateFilter
        The filter.
    u : numpy.ndarray
        Inputs with the constant 1, shape (N, m + 1), SI units.
    w : numpy.ndarray
        Their per-step form (``hold_inputs``).
    z : numpy.ndarray
        Measured outputs, shape (N, ny), SI units.
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).

    Returns
    -------
    x : numpy.ndarray
        Predicted states, shape (N, n).
    nu : numpy.ndarray
        Innovations, shape (N, ny), output units.
    """
    gain = flt.phi @ flt.K
    closed = flt.phi - gain @ flt.C
    forcing = (z - u @ flt.D.T) @ gain.T + w @ flt.gamma.T
    x = propagate(closed, forcing, x0)
    return x, z - x @ flt.C.T - u @ flt.D.T


def simulate_process_noise(model: LinearModel, values: Mapping[str, float],
                           process_noise: Mapping[str, float], time: np.ndarray,
                           inputs: np.ndarray, x0: np.ndarray | None = None,
                           seed: int = 0, hold: str = "foh") -> np.ndarray:
    """Outputs of ``model`` driven by inputs and by white process noise.

    The exact discrete equivalent Q_d of the process noise is sampled with a fixed
    ``seed``. No measurement noise is added. This is the model the filter-error method
    assumes (turbulence as white noise, e.g. a sideslip gust in the beta equation).

    Parameters
    ----------
    model : LinearModel
        The linear model.
    values : mapping of str to float
        Parameter values (missing ones take the start values).
    process_noise : mapping of str to float
        {state: F_i}, standard deviations of the continuous white noise entering each state
        equation, state units per sqrt(s).
    time : numpy.ndarray
        Sample times, s, shape (N,).
    inputs : numpy.ndarray
        Inputs in the model's order, shape (N, m), SI units.
    x0 : numpy.ndarray or None, optional
        Initial state, shape (n,); default zero.
    seed : int, optional
        Seed of the noise generator. Default 0.
    hold : str, optional
        Inputs between samples: 'foh' (default) or 'zoh'.

    Returns
    -------
    numpy.ndarray
        Outputs, shape (N, ny), SI units.

    Raises
    ------
    ValueError
        Process noise on a state the model does not have.
    """
    time = np.asarray(time, dtype=float)
    n_states = len(model.states)
    unknown = [s for s in process_noise if s not in model.states]
    if unknown:
        raise ValueError(f"process noise on unknown state(s) {', '.join(unknown)}; "
                         f"the {model.name} model has {', '.join(model.states)}")
    u = np.column_stack([np.asarray(inputs, dtype=float).reshape(len(time), -1),
                         np.ones(len(time))])
    A, B, C, D = model.matrices(values)
    dt = float(np.mean(np.diff(time)))
    F = np.diag([process_noise.get(s, 0.0) for s in model.states])
    phi, gamma, _, _ = discretize(A, B, dt, np.zeros((0, n_states, n_states)),
                                     np.zeros((0, *B.shape)), hold)
    qd = process_noise_covariance(A, F, dt)
    vals, vecs = np.linalg.eigh(qd)
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))
    noise = np.random.default_rng(seed).standard_normal((len(time), n_states)) @ root.T
    w = hold_inputs(u, hold)
    start = np.zeros(n_states) if x0 is None else np.asarray(x0, dtype=float)
    x = propagate(phi, w @ gamma.T + noise, start)
    return x @ C.T + u @ D.T


# ------------------------------------------------------------------ problem


@dataclass
class FilterProblem:
    data: Problem
    names: list[str]  # estimated: model parameters then F_<state>
    fixed: dict[str, float]  # model parameters not estimated
    noise_states: tuple[str, ...]  # states with an F parameter (free or fixed)
    fixed_noise: dict[str, float]  # F_<state> not estimated, at their values

    def split(self, theta: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
        """Model parameter values and the diagonal F matrix of a parameter vector."""
        values = {**self.data.model.start, **self.fixed}
        f_values = dict(self.fixed_noise)
        for name, value in zip(self.names, theta, strict=True):
            if name.startswith(PROCESS_NOISE_PREFIX):
                f_values[name] = value
            elif not name.startswith(MEASUREMENT_NOISE_PREFIX):
                values[name] = value
        states = self.data.model.states
        diag = [f_values.get(process_noise_name(s), 0.0) for s in states]
        return values, np.diag(np.asarray(diag, dtype=float))

    def noise(self, theta: np.ndarray, R: np.ndarray) -> np.ndarray:
        """R with the diagonal entries of the estimated sigma_<output> taken from theta."""
        R = np.array(R, dtype=float)
        outputs = self.data.model.outputs
        for name, value in zip(self.names, theta, strict=True):
            if name.startswith(MEASUREMENT_NOISE_PREFIX):
                j = outputs.index(name[len(MEASUREMENT_NOISE_PREFIX):])
                R[j, j] = value**2
        return R

    def filter(self, theta: np.ndarray, R: np.ndarray) -> SteadyStateFilter:
        values, F = self.split(theta)
        A, B, C, D = self.data.model.build(values)
        return steady_state_filter(np.real(A), np.real(B), np.real(C), np.real(D), F,
                                   self.noise(theta, R), self.data.dt, self.data.hold)


@dataclass
class FilterEvaluation:
    cost: float
    x: np.ndarray
    nu: np.ndarray
    flt: SteadyStateFilter
    gradient: np.ndarray | None = None
    information: np.ndarray | None = None
    hessian: np.ndarray | None = None
    sensitivities: np.ndarray | None = None  # dnu/dtheta (N, ny, np)
    covariance_sensitivities: np.ndarray | None = None  # dS/dtheta (np, ny, ny)
    # d/dtheta of the filter's phi, gamma, C, D, each (np, rows, columns)
    matrix_sensitivities: dict[str, np.ndarray] | None = None


def require_filter(ev: FilterEvaluation) -> SteadyStateFilter:
    """``ev``'s filter.

    Parameters
    ----------
    ev : FilterEvaluation
        An evaluation (``evaluate``).

    Returns
    -------
    SteadyStateFilter

    Raises
    ------
    ValueError
        The filter could not be built at the evaluation's parameters (no stabilising
        Riccati solution, or a model that is not finite there).
    """
    if ev.flt is None:
        raise ValueError("filter error: no steady-state Kalman filter at these parameters "
                         "(the Riccati equation has no stabilising solution, or the model "
                         "is not finite there)")
    return ev.flt


def negative_log_likelihood(nu: np.ndarray, S: np.ndarray) -> float:
    """1/2 sum nu^T S^-1 nu + N/2 ln det S (Jategaonkar eq. 5.9, constant dropped).

    Parameters
    ----------
    nu : numpy.ndarray
        Innovations, shape (N, ny).
    S : numpy.ndarray
        Innovation covariance, shape (ny, ny).

    Returns
    -------
    float
        J; infinite when S is not positive definite.
    """
    sign, logdet = np.linalg.slogdet(S)
    if sign <= 0:
        return float("inf")
    quad = np.sum(nu * np.linalg.solve(S, nu.T).T)
    return float(0.5 * quad + 0.5 * nu.shape[0] * logdet)


def evaluate(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
              sensitivities: bool) -> FilterEvaluation:
    """The filter's negative log-likelihood and innovations at ``theta`` (and their
    sensitivities if asked).

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem.
    theta : ndarray
        The model parameters (SI units).
    R : ndarray
        The measurement noise covariance (output units squared).
    x0 : ndarray
        The initial state.
    sensitivities : bool
        Whether to compute the innovations' sensitivities too.

    Returns
    -------
    FilterEvaluation
        The cost (infinite when the filter cannot be built or the innovations are not
        finite), the states, the innovations and the filter; with ``sensitivities``, the
        innovations' sensitivities and what follows from them.
    """
    d = prob.data
    try:
        flt = prob.filter(theta, R)
    except (np.linalg.LinAlgError, ValueError):
        return FilterEvaluation(float("inf"), np.empty(0), np.empty(0), None)  # type: ignore[arg-type]
    x, nu = innovations(flt, d.u, d.w, d.z, x0)
    cost = negative_log_likelihood(nu, flt.S) if np.all(np.isfinite(nu)) else float("inf")
    ev = FilterEvaluation(cost, x, nu, flt)
    if not sensitivities or not np.isfinite(cost):
        return ev
    npar = len(theta)
    mats = ("phi", "gamma", "C", "D", "K", "S")
    grads = {m: np.empty((npar, *getattr(flt, m).shape)) for m in mats}
    for j in range(npar):
        h = RELATIVE_STEP * max(abs(theta[j]), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[j] += h
        down[j] -= h
        f_up, f_down = prob.filter(up, R), prob.filter(down, R)
        for m in mats:
            grads[m][j] = (getattr(f_up, m) - getattr(f_down, m)) / (2 * h)
    phi, K, C, D = flt.phi, flt.K, flt.C, flt.D
    gain = phi @ K
    closed = phi - gain @ C
    d_gain = grads["phi"] @ K + phi @ grads["K"]
    d_closed = grads["phi"] - d_gain @ C - gain @ grads["C"]
    # sensitivity recursion of the predictor: s_{k+1} = closed s_k + forcing_k
    residual_input = d.z - d.u @ D.T
    forcing = (stacked_product(d_closed, x) + stacked_product(d_gain, residual_input)
               - np.einsum("ab,jbc,ic->iaj", gain, grads["D"], d.u)
               + stacked_product(grads["gamma"], d.w))
    s = propagate(closed, forcing, np.zeros((x.shape[1], npar)))
    dnu = -(np.matmul(C, s) + stacked_product(grads["C"], x)
            + stacked_product(grads["D"], d.u))
    S_inv = np.linalg.inv(flt.S)
    n = nu.shape[0]
    weighted = np.einsum("ab,ibj->iaj", S_inv, dnu)
    info = np.einsum("iak,ial->kl", dnu, weighted)
    dS = grads["S"]
    sd = np.einsum("ab,jbc->jac", S_inv, dS)  # S^-1 dS_j
    info += 0.5 * n * np.einsum("jab,lba->jl", sd, sd)
    V = nu.T @ nu
    grad = np.einsum("ia,iaj->j", nu, weighted)
    grad += 0.5 * n * np.einsum("jaa->j", sd) - 0.5 * np.einsum("jab,bc,ca->j", sd, S_inv, V)
    ev.gradient = grad
    ev.information = 0.5 * (info + info.T)
    ev.sensitivities, ev.covariance_sensitivities = dnu, dS
    ev.matrix_sensitivities = {m: grads[m] for m in ("phi", "gamma", "C", "D")}
    # Hessian without the expectation E[nu nu^T] = S (second derivatives of nu and S
    # dropped): differs from M when the residuals do not match S, i.e. while R is wrong
    #   H = sum dnu^T W dnu - (B + B^T) + tr(W dS_j W dS_l W V) - N/2 tr(W dS_j W dS_l),
    #   B_jl = tr(W dS_l W sum_k dnu_kj nu_k^T),  W = S^-1
    cross = np.einsum("iaj,ib->jab", dnu, nu)  # sum_k dnu_kj nu_k^T
    b = np.einsum("lab,jbc,ca->jl", sd, cross, S_inv)
    wv = S_inv @ V
    hess = (info - 0.5 * n * np.einsum("jab,lba->jl", sd, sd) - b - b.T
            + np.einsum("jab,lbc,ca->jl", sd, sd, wv) - 0.5 * n * np.einsum("jab,lba->jl", sd, sd))
    ev.hessian = 0.5 * (hess + hess.T)
    return ev
