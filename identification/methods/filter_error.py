"""Filter-error method: maximum likelihood with a steady-state Kalman filter inside.

For flights in turbulence (Jategaonkar 2015, ch. 5; Maine & Iliff 1985; Morelli & Klein
2016, ch. 6) the linear model of ``linear_models`` is given process noise:

    x_{k+1} = Phi x_k + Gamma w_k + e_k,   e_k ~ N(0, Q_d),   z_k = C x_k + D u_k + v_k,

with Phi, Gamma the exact discretisation of (A, B) used by output error (first-order hold
on the inputs), Q_d = int_0^dt e^{A s} F F^T e^{A^T s} ds the discretisation of the
continuous white process noise F n(t) (unit intensity, F diagonal; Van Loan 1978) and
v_k ~ N(0, R) the measurement noise. The steady-state predicted-state covariance P solves
the discrete algebraic Riccati equation (``scipy.linalg.solve_discrete_are``); the Kalman
gain is K = P C^T S^-1 with the innovation covariance S = C P C^T + R. The one-step
predictor

    nu_k = z_k - C x~_k - D u_k,   x~_{k+1} = Phi (x~_k + K nu_k) + Gamma w_k

gives the innovations nu, and the negative log-likelihood (Jategaonkar ch. 5)

    J(theta) = 1/2 sum_k nu_k^T S^-1 nu_k + N/2 ln det S.

Estimation is Jategaonkar's two-step relaxation:
1. with R fixed, Gauss-Newton on the derivatives, biases and the diagonal of F, with the
   Fisher information M_jl = sum_k dnu_j^T S^-1 dnu_l + N/2 tr(S^-1 dS_j S^-1 dS_l)
   (its observed form while the residuals do not yet match S) and Levenberg-Marquardt
   damping; the innovation sensitivities come from central differences of
   (Phi, Gamma, C, D, K, S), propagated through the predictor exactly;
2. R from the innovations, R = diag(1/N sum nu nu^T - C P C^T) (the measurement part of
   the innovation covariance, Maine & Iliff's mixed formulation), kept above 1 % (in
   standard deviation) of the output-error residual, then the F-compensation heuristic
   (Jategaonkar eq. 5.41), which scales each F_i with the weighted change
   sqrt(R_new / R_old) of the outputs that see state i, so that the Kalman gain of the
   next pass starts where the last one ended. The R step is damped until it lowers J, so
   both steps descend the same likelihood. While R still moves by more than 10 % the
   Gauss-Newton passes are cut to a few steps.
Both steps use the shared engine (``identification.engine``): the damped Newton step of
``gauss_newton`` on the filter's likelihood, Cramer-Rao bounds sqrt(diag M^-1) at the
converged point (R taken as known; ``bounds``, M&K eq. 6.50). Output error supplies the
start values and decides which parameters the flight cannot determine; the same checks of
``identifiability`` are repeated on the filter's information matrix, and a relaxation is
refitted without the parameters they find (``refit.refit_without_unidentifiable``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.bounds import cramer_rao_covariance, standard_errors
from flightid.identification.engine.gauss_newton import damped_newton_step
from flightid.identification.engine.refit import refit_without_unidentifiable
from flightid.identification.engine.threads import one_blas_thread
from flightid.identification.estimate import Estimate
from flightid.identification.methods import output_error as oe
from flightid.identification.methods.protocol import HeldOptions, Method, option
from flightid.identification.models import a_priori
from flightid.identification.models import structure as model_structure
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

ID = "fem"
# Euler angles follow from the rates by kinematics: turbulence does not enter them
KINEMATIC_STATES = ("phi", "theta", "psi")
PROCESS_NOISE_PREFIX = "F_"
# relative step of the central differences of the filter matrices: truncation error
# ~1e-10, rounding of the Riccati solution (~1e-13 relative) amplified to ~1e-8
RELATIVE_STEP = 1e-5
# relaxation: Gauss-Newton passes of EARLY_ITERATIONS steps while R still changes by more
# than ROUGH_NOISE_CHANGE (relative) per update, full passes after that
EARLY_ITERATIONS = 3
# smallest measurement-noise standard deviation, as a fraction of the output-error residual
# standard deviation of the same output: on real data the process noise can explain all
# of an output's innovation, which drives R to zero (K C -> I, the filter then follows the
# measured states and the method degenerates towards equation error)
MIN_NOISE_FRACTION = 0.01
ROUGH_NOISE_CHANGE = 0.1


def process_noise_name(state: str) -> str:
    """Parameter name of the process-noise standard deviation of a state equation."""
    return f"{PROCESS_NOISE_PREFIX}{state}"


@dataclass
class SteadyStateFilter:
    """Discrete model and steady-state Kalman filter of one parameter set (SI units).

    phi, gamma: discrete state and input matrices (input w_i of ``output_error.hold_inputs``);
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

    Van Loan (1978): the blocks of expm([[-A, F F^T], [0, A^T]] dt). F in state units per
    sqrt(s) (state rate per sqrt(Hz)); Q_d in state units squared.
    """
    n = A.shape[0]
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n] = -A * dt
    big[:n, n:] = F @ F.T * dt
    big[n:, n:] = A.T * dt
    e = scipy.linalg.expm(big)
    phi = e[n:, n:].T
    q = phi @ e[:n, n:]
    return 0.5 * (q + q.T)


def steady_state_filter(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                        F: np.ndarray, R: np.ndarray, dt: float,
                        hold: str = "foh") -> SteadyStateFilter:
    """Discretise (A, B) and F, solve the discrete Riccati equation, return the filter.

    Raises numpy.linalg.LinAlgError when the Riccati equation has no stabilising solution.
    """
    n = A.shape[0]
    phi, gamma, _, _ = oe.discretize(A, B, dt, np.zeros((0, n, n)),
                                     np.zeros((0, *B.shape)), hold)
    qd = process_noise_covariance(A, F, dt)
    if np.any(qd):
        # solve_discrete_are(a, b, q, r) is the control form; the filter's predicted
        # covariance is its dual with a = Phi^T, b = C^T
        P = scipy.linalg.solve_discrete_are(phi.T, C.T, qd, R)
        P = 0.5 * (P + P.T)
    else:
        P = np.zeros((n, n))
    S = C @ P @ C.T + R
    K = np.linalg.solve(S, C @ P).T  # P C^T S^-1 (S symmetric)
    return SteadyStateFilter(phi, gamma, C, D, qd, P, 0.5 * (S + S.T), K)


def innovations(flt: SteadyStateFilter, u: np.ndarray, w: np.ndarray, z: np.ndarray,
                x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Predicted states x~ (N, n) and innovations nu (N, ny) of the steady-state filter.

    u (N, m+1) inputs with the constant 1, w their per-step form (``hold_inputs``), z (N, ny)
    measured outputs, x0 the predicted state at the first sample.
    The predictor is LTI: x~_{k+1} = Phi (I - K C) x~_k + Phi K (z_k - D u_k) + Gamma w_k.
    """
    gain = flt.phi @ flt.K
    closed = flt.phi - gain @ flt.C
    forcing = (z - u @ flt.D.T) @ gain.T + w @ flt.gamma.T
    x = oe.propagate(closed, forcing, x0)
    return x, z - x @ flt.C.T - u @ flt.D.T


def simulate_process_noise(model: LinearModel, values: Mapping[str, float],
                           process_noise: Mapping[str, float], time: np.ndarray,
                           inputs: np.ndarray, x0: np.ndarray | None = None,
                           seed: int = 0, hold: str = "foh") -> np.ndarray:
    """Outputs (N, ny) of ``model`` driven by inputs (N, m) and by white process noise.

    process_noise: {state: F_i} standard deviations of the continuous white noise entering
    each state equation (state units per sqrt(s)); the exact discrete equivalent Q_d is
    sampled with a fixed ``seed``. No measurement noise is added. This is the model the
    filter-error method assumes (turbulence as white noise, e.g. a sideslip gust in the
    beta equation).
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
    phi, gamma, _, _ = oe.discretize(A, B, dt, np.zeros((0, n_states, n_states)),
                                     np.zeros((0, *B.shape)), hold)
    qd = process_noise_covariance(A, F, dt)
    vals, vecs = np.linalg.eigh(qd)
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))
    noise = np.random.default_rng(seed).standard_normal((len(time), n_states)) @ root.T
    w = oe.hold_inputs(u, hold)
    start = np.zeros(n_states) if x0 is None else np.asarray(x0, dtype=float)
    x = oe.propagate(phi, w @ gamma.T + noise, start)
    return x @ C.T + u @ D.T


# ------------------------------------------------------------------ problem


@dataclass
class _Problem:
    data: oe.Problem
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
            else:
                values[name] = value
        states = self.data.model.states
        diag = [f_values.get(process_noise_name(s), 0.0) for s in states]
        return values, np.diag(np.asarray(diag, dtype=float))

    def filter(self, theta: np.ndarray, R: np.ndarray) -> SteadyStateFilter:
        values, F = self.split(theta)
        A, B, C, D = self.data.model.build(values)
        return steady_state_filter(np.real(A), np.real(B), np.real(C), np.real(D), F, R,
                                   self.data.dt, self.data.hold)


@dataclass
class _Evaluation:
    cost: float
    x: np.ndarray
    nu: np.ndarray
    flt: SteadyStateFilter
    gradient: np.ndarray | None = None
    information: np.ndarray | None = None
    hessian: np.ndarray | None = None


def _nll(nu: np.ndarray, S: np.ndarray) -> float:
    """1/2 sum nu^T S^-1 nu + N/2 ln det S (Jategaonkar eq. 5.9, constant dropped)."""
    sign, logdet = np.linalg.slogdet(S)
    if sign <= 0:
        return float("inf")
    quad = np.sum(nu * np.linalg.solve(S, nu.T).T)
    return float(0.5 * quad + 0.5 * nu.shape[0] * logdet)


def _evaluate(prob: _Problem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
              sensitivities: bool) -> _Evaluation:
    d = prob.data
    try:
        flt = prob.filter(theta, R)
    except (np.linalg.LinAlgError, ValueError):
        return _Evaluation(float("inf"), np.empty(0), np.empty(0), None)  # type: ignore[arg-type]
    x, nu = innovations(flt, d.u, d.w, d.z, x0)
    cost = _nll(nu, flt.S) if np.all(np.isfinite(nu)) else float("inf")
    ev = _Evaluation(cost, x, nu, flt)
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
    forcing = (oe.stacked_product(d_closed, x) + oe.stacked_product(d_gain, residual_input)
               - np.einsum("ab,jbc,ic->iaj", gain, grads["D"], d.u)
               + oe.stacked_product(grads["gamma"], d.w))
    s = oe.propagate(closed, forcing, np.zeros((x.shape[1], npar)))
    dnu = -(np.matmul(C, s) + oe.stacked_product(grads["C"], x)
            + oe.stacked_product(grads["D"], d.u))
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


# ------------------------------------------------------------------ iteration


@dataclass
class _Pass:
    theta: np.ndarray
    evaluation: _Evaluation
    converged: bool
    reason: str
    iterations: int
    cost_history: list[float]


def _gauss_newton(prob: _Problem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
                  max_iterations: int, step_tol: float, cost_tol: float) -> _Pass:
    """Minimise J(theta) with R fixed: Gauss-Newton with Levenberg-Marquardt damping
    (``engine.gauss_newton.damped_newton_step`` on the filter's H, M and gradient)."""
    lam = 0.0
    history: list[float] = []

    def cost(trial: np.ndarray) -> float:
        return _evaluate(prob, trial, R, x0, sensitivities=False).cost

    for iteration in range(max_iterations + 1):
        ev = _evaluate(prob, theta, R, x0, sensitivities=True)
        history.append(ev.cost)
        if not np.isfinite(ev.cost):
            return _Pass(theta, ev, False, "the filter has no stabilising Riccati solution "
                         "at these parameters", iteration, history)
        if len(theta) == 0:
            return _Pass(theta, ev, True, "no free parameters", iteration, history)
        if iteration == max_iterations:
            return _Pass(theta, ev, False, f"no convergence in {max_iterations} iterations",
                         iteration, history)
        step = damped_newton_step(theta, ev.information, ev.hessian, -ev.gradient, ev.cost,
                                  cost, lam, step_tol)
        lam = step.lam
        if not step.accepted:
            return _Pass(theta, ev, step.at_minimum, step.reason, iteration, history)
        change = float(np.max(np.abs(step.step) / step.std))
        theta = step.theta
        if change < step_tol or ev.cost - step.cost < cost_tol:
            final = _evaluate(prob, theta, R, x0, sensitivities=True)
            history.append(final.cost)
            why = (f"parameter change below {step_tol:g} standard errors" if change < step_tol
                   else f"cost change below {cost_tol:g}")
            return _Pass(theta, final, True, why, iteration + 1, history)
    raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")


def _measurement_noise(ev: _Evaluation, lower: np.ndarray) -> np.ndarray:
    """R = diag(1/N sum nu nu^T - C P C^T), the measurement part of the innovations.

    Kept above ``lower`` (variances) so that R stays positive definite when the process
    noise explains all of an output's innovation (Jategaonkar's constraint K C <= 1).
    """
    innovation = np.mean(ev.nu**2, axis=0)
    predicted = np.diag(ev.flt.C @ ev.flt.P @ ev.flt.C.T)
    return np.diag(np.maximum(innovation - predicted, lower))


def _noise_step(prob: _Problem, theta: np.ndarray, R: np.ndarray, R_new: np.ndarray,
                ev: _Evaluation, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(theta, R) after the R update, damped until it lowers the likelihood, or None.

    The closed-form R is not the exact minimiser of J over R (Maine & Iliff's mixed
    formulation neglects the dependence of P on R), and far from convergence it can
    overshoot (an R at its lower bound with a large F); so the update is taken
    geometrically, R^(1-a) R_new^a with a = 1, 1/2, ..., 1/32, with and without the F
    compensation, and the first candidate that lowers J is kept. Both steps of the
    relaxation then lower the same likelihood, which makes the iteration monotone.
    """
    for a in (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125):
        R_try = np.diag(np.diag(R) ** (1 - a) * np.diag(R_new) ** a)
        for candidate in (_compensate_f(prob, theta, R, R_try, ev.flt.C), theta):
            cost = _evaluate(prob, candidate, R_try, x0, sensitivities=False).cost
            if np.isfinite(cost) and cost < ev.cost:
                return candidate, R_try
    return None


def _compensate_f(prob: _Problem, theta: np.ndarray, R_old: np.ndarray, R_new: np.ndarray,
                  C: np.ndarray) -> np.ndarray:
    """Jategaonkar eq. 5.41: F_i *= sum_k C_ki^2/R_k sqrt(R_new_k/R_k) / sum_k C_ki^2/R_k.

    If R and F F^T scale together the Riccati solution scales with them and the Kalman
    gain is unchanged; this keeps the gain roughly constant across the R update.
    """
    theta = theta.copy()
    r_old, r_new = np.diag(R_old), np.diag(R_new)
    weight = (C**2).T / r_old  # (n, ny)
    num = weight @ np.sqrt(r_new / r_old)
    den = weight.sum(axis=1)
    states = prob.data.model.states
    for j, name in enumerate(prob.names):
        if name.startswith(PROCESS_NOISE_PREFIX):
            i = states.index(name[len(PROCESS_NOISE_PREFIX):])
            if den[i] > 0:
                theta[j] *= num[i] / den[i]
    return theta


# ------------------------------------------------------------------ estimation


@one_blas_thread
def estimate(
    record: FlightRecord,
    model: LinearModel,
    *,
    free: Sequence[str] | None = None,
    start: Mapping[str, float] | None = None,
    process_noise: Sequence[str] | None = None,
    process_noise_start: Mapping[str, float] | None = None,
    initial_state: str = "measured",
    hold: str = "foh",
    max_iterations: int = 30,
    max_relaxations: int = 20,
    step_tolerance: float = 1e-3,
    cost_tolerance: float = 1e-6,
    noise_tolerance: float = 1e-3,
    check_identifiability: bool = True,
) -> Estimate:
    """Filter-error maximum-likelihood estimate of ``model``'s parameters from ``record``.

    free: model parameters to estimate (default all). start: a priori values overriding the
    model's (the iteration starts from an output-error fit from there). process_noise: the
    states whose equations carry process noise, each with a free F_<state> (state units per
    sqrt(s)); default every state except the Euler angles. process_noise_start: start
    values of F_<state> (default: half the output-error residual standard deviation of the
    state's channel per sqrt(s)). initial_state: 'measured' or 'zero' (the filter forgets
    it within a few samples). Values are nondimensional derivatives, SI-unit biases and
    F_<state>; standard errors are Cramer-Rao bounds of the filter's likelihood.
    Converged when a Gauss-Newton pass moved no parameter by more than ``step_tolerance``
    of its standard error and the R update changed no variance by more than
    ``noise_tolerance`` (relative).
    """
    if initial_state not in ("measured", "zero"):
        raise ValueError(
            f"filter error takes initial_state 'measured' or 'zero', got {initial_state!r} "
            "(the Kalman filter forgets the initial state, so it is not estimated)"
        )
    if start:
        model = model.with_start(**start)
    if isinstance(process_noise, str):  # 'beta' or 'beta,p,r' from the command line
        process_noise = [s.strip() for s in process_noise.split(",") if s.strip()]
    noise_states = tuple(s for s in model.states if s not in KINEMATIC_STATES) \
        if process_noise is None else tuple(process_noise)
    bad = [s for s in noise_states if s not in model.states]
    if bad:
        raise ValueError(f"process noise on unknown state(s) {', '.join(bad)}; the "
                         f"{model.name} model has states {', '.join(model.states)}")
    if not noise_states:
        raise ValueError("filter error needs process noise on at least one state; without "
                         "it the method is output error (use output_error.estimate)")
    names = list(model.parameters if free is None else free)

    # output error first: start values, measurement noise and identifiability
    oe_fit = oe.estimate(record, model, free=names, initial_state=initial_state, hold=hold,
                         check_identifiability=check_identifiability)
    data = oe.problem_from_record(record, model, initial_state, hold)
    unidentifiable = dict(oe_fit.unidentifiable)
    R = np.diag([oe_fit.fit["noise_std"][o] ** 2 for o in model.outputs])
    f_start = {}
    for s in noise_states:
        channel = model.state_channels.get(s, s)
        sigma = oe_fit.fit["noise_std"].get(channel, np.sqrt(np.mean(np.diag(R))))
        f_start[process_noise_name(s)] = 0.5 * sigma
    for k, v in (process_noise_start or {}).items():
        if k not in f_start:
            raise ValueError(f"process_noise_start has {k!r}; process-noise parameters are "
                             f"{', '.join(f_start)}")
        f_start[k] = float(v)
    values = {n: (oe_fit[n] if n in oe_fit.names else model.start[n]) for n in names}
    values.update(f_start)
    all_names = [n for n in names if n not in unidentifiable] + list(f_start)

    # lower bound of R: a fixed fraction of the output-error residual variance
    floor = np.maximum(data.noise_floor, MIN_NOISE_FRACTION**2 * np.diag(R))

    def fit(active: list[str], current: dict[str, float]) -> _Relaxed:
        # parameters found unidentifiable stay at the values of the fit that found them,
        # and the next relaxation starts from its R
        nonlocal R
        prob = _Problem(data, active,
                        {n: v for n, v in {**model.start, **current}.items()
                         if n in model.parameters and n not in active},
                        noise_states,
                        {n: 0.0 for n in f_start if n not in active})
        theta = np.array([current[n] for n in active])
        relaxed = _relax(prob, theta, R, data.x0, max_iterations, max_relaxations,
                         step_tolerance, cost_tolerance, noise_tolerance, floor)
        R = relaxed.R
        return relaxed

    def singular(active: list[str], relaxed: _Relaxed) -> dict[str, str]:
        if not (check_identifiability and active):
            return {}
        keep = [n for n in active if n.startswith(("bias_", PROCESS_NOISE_PREFIX))]
        return ident.unidentifiable(active, relaxed.information, relaxed.theta,
                                    prefer_keep=keep)

    final, unidentifiable = refit_without_unidentifiable(all_names, values, fit, singular,
                                                         known=unidentifiable)
    return _result(final.problem, final, unidentifiable, oe_fit)


@dataclass
class _Relaxed:
    problem: _Problem
    theta: np.ndarray
    R: np.ndarray
    evaluation: _Evaluation
    information: np.ndarray
    converged: bool
    reason: str
    passes: int
    iterations: int
    cost_history: list[float]
    noise_history: list[np.ndarray]
    lower: np.ndarray

    @property
    def values(self) -> dict[str, float]:
        """{name: value} of the estimated parameters."""
        return dict(zip(self.problem.names, self.theta, strict=True))


def _relax(prob: _Problem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
           max_iterations: int, max_relaxations: int, step_tol: float, cost_tol: float,
           noise_tol: float, floor: np.ndarray) -> _Relaxed:
    """Alternate Gauss-Newton passes (R fixed) and R updates with F compensation."""
    history: list[float] = []
    noise_history = [np.diag(R).copy()]
    iterations = 0
    converged, reason = False, f"R still changing after {max_relaxations} relaxation steps"
    change = np.inf
    passes = 0
    while passes < max_relaxations:
        passes += 1
        # while R is far from its final value the likelihood surface in theta is skewed
        # and Gauss-Newton creeps: a few steps, then a new R (Jategaonkar sec. 5.5)
        early = change > ROUGH_NOISE_CHANGE
        gn = _gauss_newton(prob, theta, R, x0, EARLY_ITERATIONS if early else max_iterations,
                           step_tol, cost_tol)
        iterations += gn.iterations
        history.extend(gn.cost_history)
        theta = gn.theta
        if not gn.converged and not (early and np.isfinite(gn.evaluation.cost)):
            converged, reason = False, gn.reason
            break
        R_new = _measurement_noise(gn.evaluation, floor)
        change = float(np.max(np.abs(np.diag(R_new) / np.diag(R) - 1.0)))
        if change < noise_tol and gn.converged:
            converged = True
            reason = (f"{gn.reason}; measurement noise changed by less than {noise_tol:g} "
                      "(relative)")
            break
        step = _noise_step(prob, theta, R, R_new, gn.evaluation, x0)
        if step is None:
            if not gn.converged:
                change = 0.0  # finish the Gauss-Newton pass before trying R again
                continue
            # no R between the old and the new one lowers the likelihood: R is at its
            # optimum for these parameters, as far as this update can tell
            converged = True
            reason = f"{gn.reason}; no update of the measurement noise lowers the cost"
            break
        theta, R_next = step
        change = float(np.max(np.abs(np.diag(R_next) / np.diag(R) - 1.0)))
        R = R_next
        noise_history.append(np.diag(R).copy())
    # F enters only through F F^T: report the non-negative root
    for j, name in enumerate(prob.names):
        if name.startswith(PROCESS_NOISE_PREFIX):
            theta[j] = abs(theta[j])
    final = _evaluate(prob, theta, R, x0, sensitivities=True)
    info = final.information if final.information is not None else np.zeros((0, 0))
    return _Relaxed(prob, theta, R, final, info, converged, reason, passes, iterations, history,
                    noise_history, floor)


def _result(prob: _Problem, fit: _Relaxed, unidentifiable: dict[str, str],
            oe_fit: Estimate) -> Estimate:
    names = prob.names
    d = prob.data
    ev = fit.evaluation
    if names:
        cov = cramer_rao_covariance(fit.information)
        cov = 0.5 * (cov + cov.T)
    else:
        cov = np.zeros((0, 0))
    std = standard_errors(cov)
    predicted = d.z - ev.nu
    outputs = {
        name: {"measured": d.z[:, j], "model": predicted[:, j], "residual": ev.nu[:, j]}
        for j, name in enumerate(d.model.outputs)
    }
    spread = np.sum((d.z - d.z.mean(axis=0)) ** 2, axis=0)
    r2 = {o: float(1 - np.sum(ev.nu[:, j] ** 2) / spread[j]) if spread[j] > 0
          else float("nan") for j, o in enumerate(d.model.outputs)}
    outs = d.model.outputs
    fit_stats = {
        "model": d.model.name,
        "converged": fit.converged,
        "reason": fit.reason,
        "iterations": fit.iterations,
        "relaxation_steps": fit.passes,
        "cost_history": list(fit.cost_history),
        "cost": ev.cost,
        "noise_std": {o: float(np.sqrt(fit.R[j, j])) for j, o in enumerate(outs)},
        "noise_at_lower_bound": [o for j, o in enumerate(outs)
                                 if fit.R[j, j] <= fit.lower[j] * (1 + 1e-9)],
        "noise_covariance": fit.R,
        "noise_history": [dict(zip(outs, np.sqrt(r).tolist(), strict=True))
                          for r in fit.noise_history],
        "innovation_std": {o: float(np.sqrt(ev.flt.S[j, j])) for j, o in enumerate(outs)},
        "innovation_covariance": ev.flt.S,
        "kalman_gain": ev.flt.K,
        "kalman_gain_times_C": np.diag(ev.flt.K @ ev.flt.C),
        "process_noise_states": list(prob.noise_states),
        "R2_per_output": r2,
        "R2": float(np.nanmean(list(r2.values()))),
        "fixed": {n: float(v) for n, v in {**prob.fixed, **prob.fixed_noise}.items()},
        "std_kind": "cramer-rao (filter-error likelihood, R fixed)",
        "samples": int(d.z.shape[0]),
        "high_correlations": ident.high_correlations(names, cov, 0.9) if names else [],
        "output_error": {"cost": oe_fit.fit["cost"], "converged": oe_fit.fit["converged"]},
    }
    return Estimate(
        method=ID,
        names=list(names),
        values=fit.theta.copy(),
        std=std,
        covariance=cov,
        fit=fit_stats,
        unidentifiable=dict(unidentifiable),
        outputs=outputs,
        time=d.time.copy(),
    )


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Options(HeldOptions):
    """Options of ``--method fem``."""

    free: list[str] | None = option(None, "parameters to estimate (default: all not held)")
    start: dict[str, float] | None = option(None, "start (a priori) values")
    process_noise: list[str] | None = option(
        None, "states with process noise (default: all but the Euler angles)")
    process_noise_start: dict[str, float] | None = option(
        None, "start values of F_<state> (state units per sqrt(s))")
    initial_state: str = option("measured", "'measured' or 'zero' (the filter forgets it)")
    hold: str = option("foh", "inputs between samples: 'foh' (linear) or 'zoh' (held)")
    max_iterations: int = option(30, "Gauss-Newton iterations per relaxation")
    max_relaxations: int = option(20, "limit of alternating parameter / R updates")
    step_tolerance: float = option(1e-3, "converged when no step exceeds this many std")
    cost_tolerance: float = option(1e-6, "or when the cost changes less than this (relative)")
    noise_tolerance: float = option(1e-3, "and R changes less than this (relative)")
    check_identifiability: bool = option(True, "report parameters the data cannot determine")


def run(record: FlightRecord, model: str = "lateral", options: Options | None = None
        ) -> Estimate:
    """Filter error with a linear-model preset ('lateral', 'longitudinal', 'short_period')
    at the record's reference condition, a priori parameters held."""
    options = options or Options()
    linear, free, held = a_priori.linear_model(
        model_structure.linear(model), record, options.derivatives, options.a_priori,
        "filter error")
    est = estimate(
        record, linear, free=free if options.free is None else list(options.free),
        start=options.start, process_noise=options.process_noise,
        process_noise_start=options.process_noise_start,
        initial_state=options.initial_state, hold=options.hold,
        max_iterations=options.max_iterations, max_relaxations=options.max_relaxations,
        step_tolerance=options.step_tolerance, cost_tolerance=options.cost_tolerance,
        noise_tolerance=options.noise_tolerance,
        check_identifiability=options.check_identifiability)
    est.fit["a_priori"] = a_priori.describe(record, held)
    return est


METHOD = Method(
    id=ID, name="filter error",
    summary="maximum likelihood with a steady-state Kalman filter in the loop: process "
            "noise (turbulence) and measurement noise together",
    reference="Jategaonkar, Flight Vehicle System Identification: A Time-Domain "
              "Methodology, 2nd ed., 2015, ch. 5; Morelli & Klein 2016 ch. 6",
    options=Options, models=model_structure.LINEAR, default_model="lateral",
    channels=model_structure.linear_channels, run=run, contract_model="lateral",
)
