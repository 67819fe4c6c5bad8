"""The filter-error iteration: one Gauss-Newton pass with the measurement noise R fixed,
the measurement-noise step with the F-compensation (Jategaonkar 2015 ch. 5, eq. 5.41),
and the robust bounds of the converged fit (the sandwich of the per-sample scores).
The filter and its likelihood are ``kalman_filter``; ``relaxation`` alternates them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.engine.gauss_newton import damped_newton_step
from flightid.identification.methods.filter_error.kalman_filter import (
    PROCESS_NOISE_PREFIX,
    FilterEvaluation,
    FilterProblem,
    evaluate,
    require_filter,
)


@dataclass
class FilterPass:
    theta: np.ndarray
    evaluation: FilterEvaluation
    converged: bool
    reason: str
    iterations: int
    cost_history: list[float]


def gauss_newton_pass(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
                  max_iterations: int, step_tol: float, cost_tol: float) -> FilterPass:
    """Minimise J(theta) with R fixed.

    Gauss-Newton with Levenberg-Marquardt damping
    (``engine.gauss_newton.damped_newton_step`` on the filter's H, M and gradient).
    Converged when no parameter moved by more than ``step_tol`` of its standard error, or
    when J fell by less than ``cost_tol`` times max(|J|, 1) (relative).

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem.
    theta : numpy.ndarray
        Start values of the estimated parameters, shape (np,).
    R : numpy.ndarray
        Measurement-noise covariance, shape (ny, ny), held fixed.
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).
    max_iterations : int
        Iteration limit (>= 1).
    step_tol : float
        Step tolerance, standard errors.
    cost_tol : float
        Relative cost tolerance.

    Returns
    -------
    FilterPass
        Parameters, evaluation with sensitivities, convergence flag and reason, iterations
        and the cost history.

    Raises
    ------
    ValueError
        ``max_iterations`` is below 1 with free parameters.
    """
    lam = 0.0
    history: list[float] = []

    def cost(trial: np.ndarray) -> float:
        return evaluate(prob, trial, R, x0, sensitivities=False).cost

    for iteration in range(max_iterations + 1):
        ev = evaluate(prob, theta, R, x0, sensitivities=True)
        history.append(ev.cost)
        if not np.isfinite(ev.cost):
            return FilterPass(theta, ev, False, "the filter has no stabilising Riccati solution "
                         "at these parameters", iteration, history)
        if len(theta) == 0:
            return FilterPass(theta, ev, True, "no free parameters", iteration, history)
        if iteration == max_iterations:
            return FilterPass(theta, ev, False, f"no convergence in {max_iterations} iterations",
                         iteration, history)
        step = damped_newton_step(theta, ev.information, ev.hessian, -ev.gradient, ev.cost,
                                  cost, lam, step_tol)
        lam = step.lam
        if not step.accepted:
            return FilterPass(theta, ev, step.at_minimum, step.reason, iteration, history)
        change = float(np.max(np.abs(step.step) / step.std))
        theta = step.theta
        if change < step_tol or ev.cost - step.cost < cost_tol * max(abs(ev.cost), 1.0):
            final = evaluate(prob, theta, R, x0, sensitivities=True)
            history.append(final.cost)
            why = (f"parameter change below {step_tol:g} standard errors" if change < step_tol
                   else f"cost change below {cost_tol:g} (relative)")
            return FilterPass(theta, final, True, why, iteration + 1, history)
    raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")


def measurement_noise(ev: FilterEvaluation, lower: np.ndarray) -> np.ndarray:
    """R = diag(1/N sum nu nu^T - C P C^T), the measurement part of the innovations.

    Kept above ``lower`` so that R stays positive definite when the process noise explains
    all of an output's innovation (Jategaonkar's constraint K C <= 1).

    Parameters
    ----------
    ev : FilterEvaluation
        The filter's evaluation (innovations and filter).
    lower : numpy.ndarray
        Lower bound of each variance, shape (ny,), output units squared.

    Returns
    -------
    numpy.ndarray
        Diagonal R, shape (ny, ny), output units squared.
    """
    innovation = np.mean(ev.nu**2, axis=0)
    flt = require_filter(ev)
    predicted = np.diag(flt.C @ flt.P @ flt.C.T)
    return np.diag(np.maximum(innovation - predicted, lower))


def noise_step(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, R_new: np.ndarray,
                ev: FilterEvaluation, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(theta, R) after the R update, damped until it lowers the likelihood.

    The closed-form R is not the exact minimiser of J over R (Maine & Iliff's mixed
    formulation neglects the dependence of P on R), and far from convergence it can
    overshoot (an R at its lower bound with a large F); so the update is taken
    geometrically, R^(1-a) R_new^a with a = 1, 1/2, ..., 1/32, with and without the F
    compensation, and the first candidate that lowers J is kept. Both steps of the
    relaxation then lower the same likelihood, which makes the iteration monotone.

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem.
    theta : numpy.ndarray
        Current parameters, shape (np,).
    R : numpy.ndarray
        Current measurement-noise covariance, shape (ny, ny).
    R_new : numpy.ndarray
        Closed-form update (``measurement_noise``), shape (ny, ny).
    ev : FilterEvaluation
        The evaluation at (theta, R), whose cost must be lowered.
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).

    Returns
    -------
    tuple of numpy.ndarray or None
        (theta, R) of the first candidate that lowers J; None when none does.
    """
    for a in (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125):
        R_try = np.diag(np.diag(R) ** (1 - a) * np.diag(R_new) ** a)
        for candidate in (compensate_process_noise(prob, theta, R, R_try, require_filter(ev).C),
                          theta):
            cost = evaluate(prob, candidate, R_try, x0, sensitivities=False).cost
            if np.isfinite(cost) and cost < ev.cost:
                return candidate, R_try
    return None


def compensate_process_noise(prob: FilterProblem, theta: np.ndarray, R_old: np.ndarray,
                             R_new: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Jategaonkar eq. 5.41: F_i *= sum_k C_ki^2/R_k sqrt(R_new_k/R_k) / sum_k C_ki^2/R_k.

    If R and F F^T scale together the Riccati solution scales with them and the Kalman
    gain is unchanged; this keeps the gain roughly constant across the R update.

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem (names the F_<state> parameters).
    theta : numpy.ndarray
        Parameters, shape (np,).
    R_old : numpy.ndarray
        Measurement-noise covariance before the update, shape (ny, ny).
    R_new : numpy.ndarray
        After the update, shape (ny, ny).
    C : numpy.ndarray
        Output matrix, shape (ny, n).

    Returns
    -------
    numpy.ndarray
        A copy of ``theta`` with the F_<state> entries scaled.
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



def score_contributions(sensitivities: np.ndarray, covariance_sensitivities: np.ndarray,
                        innovations: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Per-sample gradient of J: g_k = dnu_k^T W nu_k + 1/2 tr(W dS_j) - 1/2 nu_k^T W dS_j W nu_k.

    W = S^-1; their sum is the gradient of ``evaluate``.

    Parameters
    ----------
    sensitivities : numpy.ndarray
        dnu/dtheta, shape (N, ny, np).
    covariance_sensitivities : numpy.ndarray
        dS/dtheta, shape (np, ny, ny).
    innovations : numpy.ndarray
        nu, shape (N, ny).
    S : numpy.ndarray
        Innovation covariance, shape (ny, ny).

    Returns
    -------
    numpy.ndarray
        g, shape (N, np).
    """
    weight = np.linalg.inv(S)
    wnu = innovations @ weight
    g = np.einsum("iaj,ia->ij", sensitivities, wnu)
    g += 0.5 * np.einsum("ab,jba->j", weight, covariance_sensitivities)[None, :]
    g -= 0.5 * np.einsum("ia,jab,ib->ij", wnu, covariance_sensitivities, wnu)
    return g



def robust_covariance(information: np.ndarray, sensitivities: np.ndarray,
                      covariance_sensitivities: np.ndarray, innovations: np.ndarray,
                      S: np.ndarray) -> np.ndarray:
    """Parameter covariance of the filter-error estimate when the filter's noise model is
    not the flight's, from the spread of the per-sample scores g_k.

    The sandwich M^-1 G M^-1 with the information matrix M and the middle
    G = sum_k g_k g_k^T (``score_contributions``, centred) (Huber 1967; White, "Maximum
    likelihood estimation of misspecified models", Econometrica 50, 1982, with M for the
    Hessian as in Morelli & Klein 2016 eq. 6.54). When the model is right E[G] = M and it
    is the Cramer-Rao bound M^-1 (Jategaonkar 2015 eq. 5.22). The sandwich with the
    Hessian H of J in place of M is not used: H here drops the second derivatives of nu
    and S, and on flights where a noise parameter is nearly unidentifiable (the vane's
    sigma_beta estimated near 0) it is nearly singular; on the Navion demo card in light
    turbulence it put one flight's bounds in 29 at 15-180 times the others' (a heavy tail
    of bounds that does not follow the errors: docs/montecarlo.md, "Filter error: the
    bounds' heavy tail").

    Parameters
    ----------
    information : numpy.ndarray
        Information matrix M, shape (np, np).
    sensitivities : numpy.ndarray
        dnu/dtheta, shape (N, ny, np); carries the Kalman gain's dependence on the
        parameters.
    covariance_sensitivities : numpy.ndarray
        dS/dtheta, shape (np, ny, ny).
    innovations : numpy.ndarray
        nu, shape (N, ny).
    S : numpy.ndarray
        Innovation covariance, shape (ny, ny).

    Returns
    -------
    numpy.ndarray
        Covariance, shape (np, np), parameter units squared; symmetric.
    """
    g = score_contributions(sensitivities, covariance_sensitivities, innovations, S)
    g -= g.mean(axis=0)
    m_inv = np.linalg.inv(information)
    cov = m_inv @ (g.T @ g) @ m_inv
    return 0.5 * (cov + cov.T)
