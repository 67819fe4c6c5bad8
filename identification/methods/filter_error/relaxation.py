"""The filter error's fit of the derivatives with the process and measurement noise:
Jategaonkar's relaxation (2015 sec. 5.8: Gauss-Newton passes with R fixed, then the
closed-form R update with F compensation) and the joint Gauss-Newton on the full
likelihood (Maine & Iliff 1985) from two starts, the lower J kept."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.methods.filter_error.iteration import (
    gauss_newton_pass,
    measurement_noise,
    noise_step,
)
from flightid.identification.methods.filter_error.kalman_filter import (
    MEASUREMENT_NOISE_PREFIX,
    PROCESS_NOISE_PREFIX,
    FilterEvaluation,
    FilterProblem,
    evaluate,
    is_noise_parameter,
)

# relaxation: Gauss-Newton passes of EARLY_ITERATIONS steps while R still changes by more
# than ROUGH_NOISE_CHANGE (relative) per update, full passes after that
EARLY_ITERATIONS = 3
ROUGH_NOISE_CHANGE = 0.1


@dataclass
class Relaxed:
    problem: FilterProblem
    theta: np.ndarray
    R: np.ndarray
    evaluation: FilterEvaluation
    information: np.ndarray
    converged: bool
    reason: str
    passes: int
    iterations: int
    cost_history: list[float]
    noise_history: list[np.ndarray]
    lower: np.ndarray
    start: str = "output error"
    start_costs: dict[str, float] | None = None

    @property
    def values(self) -> dict[str, float]:
        """{name: value} of the estimated parameters."""
        return dict(zip(self.problem.names, self.theta, strict=True))


def joint(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
           max_iterations: int, step_tol: float, cost_tol: float, floor: np.ndarray
           ) -> Relaxed:
    """Gauss-Newton on the derivatives, biases, F and the measurement-noise standard
    deviations together: the likelihood's own minimum over R (Maine & Iliff 1985).

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem; its names include the sigma_<output> parameters.
    theta : numpy.ndarray
        Start values, shape (np,).
    R : numpy.ndarray
        Measurement-noise covariance, shape (ny, ny); the entries of the estimated
        sigma_<output> are taken from ``theta``.
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).
    max_iterations : int
        Gauss-Newton iteration limit.
    step_tol : float
        Step tolerance, standard errors.
    cost_tol : float
        Relative cost tolerance.
    floor : numpy.ndarray
        Noise floor of each output variance, shape (ny,), reported with the fit.

    Returns
    -------
    Relaxed
        The fit: parameters (noise standard deviations non-negative), R, evaluation,
        information matrix, convergence and histories.
    """
    gn = gauss_newton_pass(prob, theta, R, x0, max_iterations, step_tol, cost_tol)
    theta = gn.theta.copy()
    for j, name in enumerate(prob.names):
        if is_noise_parameter(name):
            theta[j] = abs(theta[j])
    R = prob.noise(theta, R)
    final = evaluate(prob, theta, R, x0, sensitivities=True)
    info = final.information if final.information is not None else np.zeros((0, 0))
    return Relaxed(prob, theta, R, final, info, gn.converged, gn.reason, 1, gn.iterations,
                    list(gn.cost_history), [np.diag(R).copy()], floor)


def two_starts(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
                max_iterations: int, max_relaxations: int, step_tol: float, cost_tol: float,
                noise_tol: float, floor: np.ndarray) -> Relaxed:
    """The joint Gauss-Newton from the output-error start and from the relaxation's end
    point (Jategaonkar 2015 sec. 5.8), the lower J kept: J has several minima in F, R.

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem, with the sigma_<output> parameters.
    theta : numpy.ndarray
        Output-error start values, shape (np,).
    R : numpy.ndarray
        Start measurement-noise covariance, shape (ny, ny).
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).
    max_iterations : int
        Gauss-Newton iteration limit per pass.
    max_relaxations : int
        Limit of relaxation steps.
    step_tol : float
        Step tolerance, standard errors.
    cost_tol : float
        Relative cost tolerance.
    noise_tol : float
        Relative change of R below which the relaxation has converged.
    floor : numpy.ndarray
        Lower bound of each output variance, shape (ny,).

    Returns
    -------
    Relaxed
        The fit of lower J; ``start`` names the winning start, ``start_costs`` the J of each
        (and of the relaxation alone).
    """
    sigma = np.array([n.startswith(MEASUREMENT_NOISE_PREFIX) for n in prob.names])
    relax_prob = FilterProblem(prob.data, [n for n, s in zip(prob.names, sigma, strict=True)
                                           if not s],
                               prob.fixed, prob.noise_states, prob.fixed_noise)
    relaxed = relax(relax_prob, theta[~sigma], R, x0, max_iterations, max_relaxations,
                     step_tol, cost_tol, noise_tol, floor)
    fits = {"output error": joint(prob, theta, R, x0, max_iterations, step_tol, cost_tol,
                                   floor)}
    if np.isfinite(relaxed.evaluation.cost):
        from_relaxed = theta.copy()
        from_relaxed[~sigma] = relaxed.theta
        outputs = prob.data.model.outputs
        from_relaxed[sigma] = [np.sqrt(relaxed.R[j, j]) for j in (
            outputs.index(n[len(MEASUREMENT_NOISE_PREFIX):]) for n, s in
            zip(prob.names, sigma, strict=True) if s)]
        fits["relaxation"] = joint(prob, from_relaxed, relaxed.R, x0, max_iterations,
                                    step_tol, cost_tol, floor)
    costs = {k: float(f.evaluation.cost) for k, f in fits.items()}
    best = min(costs, key=lambda k: costs[k] if np.isfinite(costs[k]) else np.inf)
    fit = fits[best]
    fit.start, fit.start_costs = best, {**costs, "relaxation alone": relaxed.evaluation.cost}
    fit.passes += relaxed.passes
    return fit


def relax(prob: FilterProblem, theta: np.ndarray, R: np.ndarray, x0: np.ndarray,
           max_iterations: int, max_relaxations: int, step_tol: float, cost_tol: float,
           noise_tol: float, floor: np.ndarray) -> Relaxed:
    """Alternate Gauss-Newton passes (R fixed) and R updates with F compensation.

    Parameters
    ----------
    prob : FilterProblem
        The filter-error problem (without sigma_<output> parameters).
    theta : numpy.ndarray
        Start values, shape (np,).
    R : numpy.ndarray
        Start measurement-noise covariance, shape (ny, ny).
    x0 : numpy.ndarray
        Predicted state at the first sample, shape (n,).
    max_iterations : int
        Gauss-Newton iteration limit per pass.
    max_relaxations : int
        Limit of relaxation steps.
    step_tol : float
        Step tolerance, standard errors.
    cost_tol : float
        Relative cost tolerance.
    noise_tol : float
        Relative change of R below which it has converged.
    floor : numpy.ndarray
        Lower bound of each output variance, shape (ny,).

    Returns
    -------
    Relaxed
        The fit: parameters (F non-negative), R, evaluation, information matrix,
        convergence and reason, passes, iterations and the cost and noise histories.
    """
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
        gn = gauss_newton_pass(prob, theta, R, x0, EARLY_ITERATIONS if early else max_iterations,
                           step_tol, cost_tol)
        iterations += gn.iterations
        history.extend(gn.cost_history)
        theta = gn.theta
        if not gn.converged and not (early and np.isfinite(gn.evaluation.cost)):
            converged, reason = False, gn.reason
            break
        R_new = measurement_noise(gn.evaluation, floor)
        change = float(np.max(np.abs(np.diag(R_new) / np.diag(R) - 1.0)))
        if change < noise_tol and gn.converged:
            converged = True
            reason = (f"{gn.reason}; measurement noise changed by less than {noise_tol:g} "
                      "(relative)")
            break
        step = noise_step(prob, theta, R, R_new, gn.evaluation, x0)
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
    final = evaluate(prob, theta, R, x0, sensitivities=True)
    info = final.information if final.information is not None else np.zeros((0, 0))
    return Relaxed(prob, theta, R, final, info, converged, reason, passes, iterations, history,
                    noise_history, floor)
