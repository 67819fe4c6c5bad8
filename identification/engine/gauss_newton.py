"""Damped Newton steps and the output-error maximum-likelihood optimiser.

Morelli & Klein (2016) sec. 6.2 and Jategaonkar (2015) ch. 4: Gauss-Newton (modified
Newton-Raphson) on the negative log-likelihood with Levenberg-Marquardt damping.
``damped_newton_step`` is the step both optimisers take (output error here, filter error
in ``methods.filter_error`` with its own likelihood); ``maximum_likelihood`` minimises the
output-error cost with the measurement-noise covariance R concentrated out (re-estimated
from the residuals at every iteration, the relaxation algorithm of M&K eq. 6.27).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from flightid.identification.engine.likelihood import (
    concentrated_cost,
    concentrated_hessian,
    information_matrix,
    noise_covariance,
)

# Levenberg-Marquardt: damping trials per step (lambda grows tenfold from 1e-3 each)
DAMPING_TRIALS = 14


@dataclass
class DampedStep:
    """Outcome of one damped Newton step.

    accepted: a step lowered the cost (else ``theta`` is the unchanged start);
    theta: parameters after the step; step: the change (parameter units);
    cost: the cost at ``theta`` (accepted) or the start cost; lam: the damping for the next
    step; std: Cramer-Rao scale sqrt(diag M^-1) of each parameter at the start (parameter
    units, to measure the step); at_minimum: when rejected, whether the undamped
    Gauss-Newton step is below the step tolerance (in standard errors); reason: why
    rejected ("" when accepted).
    """

    accepted: bool
    theta: np.ndarray
    step: np.ndarray
    cost: float
    lam: float
    std: np.ndarray
    at_minimum: bool = False
    reason: str = ""


def damped_newton_step(
    theta: np.ndarray, information: np.ndarray, hessian: np.ndarray, descent: np.ndarray,
    cost0: float, cost: Callable[[np.ndarray], float], lam: float, step_tol: float,
) -> DampedStep:
    """One Levenberg-Marquardt-damped Newton step that lowers ``cost`` (or none).

    The problem is scaled to a unit diagonal of M; H is used when it is positive definite, M
    otherwise (M&K sec. 6.2). The damping ``lam`` grows tenfold (from 1e-3) until a step does
    not raise the cost, and shrinks tenfold after an accepted step.

    Parameters
    ----------
    theta : numpy.ndarray
        The parameter vector, parameter units; shape (np,).
    information : numpy.ndarray
        The Gauss-Newton matrix M at ``theta``; shape (np, np).
    hessian : numpy.ndarray
        The Newton matrix H of the cost at ``theta``; shape (np, np).
    descent : numpy.ndarray
        -dJ/dtheta at ``theta``; shape (np,).
    cost0 : float
        J(theta), nondimensional.
    cost : callable
        The cost of a trial parameter vector (not finite when the model cannot be evaluated
        there).
    lam : float
        The damping to start from, 1.
    step_tol : float
        The Newton step, in standard errors, below which a failed search counts as at the
        minimum.

    Returns
    -------
    DampedStep
        Whether a step was accepted, the new parameters, the step, its cost, the next damping,
        the parameters' standard errors and, when none was accepted, why.
    """
    scale = np.sqrt(np.clip(np.diag(information), 0.0, None))
    scale = np.where(scale > 0, scale, 1.0)
    info_n = information / np.outer(scale, scale)
    hess_n = hessian / np.outer(scale, scale)
    try:
        np.linalg.cholesky(hess_n)
    except np.linalg.LinAlgError:
        hess_n = info_n
    descent_n = descent / scale
    eye = np.eye(len(theta))
    for _ in range(DAMPING_TRIALS):
        step = np.linalg.lstsq(hess_n + lam * eye, descent_n, rcond=None)[0] / scale
        trial = theta + step
        trial_cost = cost(trial)
        if np.isfinite(trial_cost) and trial_cost <= cost0:
            break
        lam = max(10.0 * lam, 1e-3)
    else:
        newton = np.linalg.lstsq(info_n, descent_n, rcond=None)[0]
        at_minimum = bool(np.max(np.abs(newton)) < step_tol)
        reason = "no damped step lowers the cost: " + (
            "at the minimum to within rounding" if at_minimum
            else "stopped away from a minimum")
        return DampedStep(False, theta, np.zeros_like(theta), cost0, lam,
                          np.full(len(theta), np.nan), at_minimum, reason)
    # the change relative to each parameter's Cramer-Rao bound sqrt(diag M^-1)
    std = np.sqrt(np.abs(np.diag(np.linalg.pinv(info_n)))) / scale
    return DampedStep(True, trial, step, trial_cost, lam / 10.0 if lam > 1e-6 else 0.0, std)


@dataclass
class MaximumLikelihoodFit:
    """The state of a finished maximum-likelihood fit (SI units of the outputs).

    names, values: the estimated parameters; y (N, ny) outputs and sens (N, ny, np) their
    sensitivities at ``values``; residuals z - y; noise: R (ny, ny); information: M;
    convergence flag, reason, iterations and the histories of the cost N/2 ln det R and of
    the step (in standard errors).
    """

    names: list[str]
    values: dict[str, float]
    y: np.ndarray
    sens: np.ndarray
    residuals: np.ndarray
    noise: np.ndarray
    information: np.ndarray
    converged: bool
    reason: str
    iterations: int
    cost_history: list[float]
    step_history: list[float]


def maximum_likelihood(
    z: np.ndarray, floor: np.ndarray,
    outputs_and_sensitivities: Callable[[dict[str, float]], tuple[np.ndarray, np.ndarray]],
    outputs: Callable[[dict[str, float]], np.ndarray],
    names: list[str], values: Mapping[str, float], max_iterations: int,
    full: bool, step_tol: float, cost_tol: float,
) -> MaximumLikelihoodFit:
    """Newton-Raphson on the ML cost with R concentrated out, Levenberg-Marquardt safeguard.

    Used by the linear and the nonlinear 6-DOF output error and by flight path
    reconstruction. R is re-estimated from the residuals at every iteration (M&K eq. 6.26).
    The Newton matrix is the Gauss-Newton information matrix M (M&K eq. 6.33) minus the term
    from the dependence of R on theta (``likelihood.concentrated_hessian``), which restores
    fast convergence when the residuals are large (real data), where the plain relaxation
    algorithm creeps along one direction. H is used when it is positive definite, M
    otherwise; a step is accepted only if it lowers N/2 ln det R.

    Parameters
    ----------
    z : numpy.ndarray
        The measurements, SI units; shape (N, ny).
    floor : numpy.ndarray
        The smallest admitted noise variance per output; shape (ny,).
    outputs_and_sensitivities : callable
        Maps the parameter values {name: value} to y (N, ny) and dy/dtheta
        (N, ny, len(names)).
    outputs : callable
        Maps the parameter values to y (N, ny) alone.
    names : list of str
        The parameters estimated.
    values : mapping of str to float
        The start of every name, parameter units (other entries are ignored).
    max_iterations : int
        The iteration limit.
    full : bool
        Estimate the off-diagonal terms of R.
    step_tol : float
        Converged when the last step moved no parameter by more than this many standard
        errors.
    cost_tol : float
        Converged when the cost changed by less than this, nondimensional.

    Returns
    -------
    MaximumLikelihoodFit
        The fitted values, outputs, sensitivities, residuals, noise covariance, information
        matrix and the iteration history.
    """
    n_samples = z.shape[0]
    cost_history: list[float] = []
    step_history: list[float] = []
    lam = 0.0
    converged, reason = False, f"no convergence in {max_iterations} iterations"
    theta = np.array([values[n] for n in names], dtype=float)
    iterations = 0

    def trial_cost(trial: np.ndarray) -> float:
        # a trial step may make the model unstable: its outputs overflow, its cost is
        # not finite and the step is rejected, so the overflow is expected here
        with np.errstate(over="ignore", invalid="ignore"):
            return concentrated_cost(z - outputs(dict(zip(names, trial, strict=True))),
                                     full, floor)

    while True:
        current = dict(zip(names, theta, strict=True))
        y, sens = outputs_and_sensitivities(current)
        v = z - y
        noise = noise_covariance(v, full, floor)
        weight = np.linalg.inv(noise)
        cost_history.append(0.5 * n_samples * float(np.linalg.slogdet(noise)[1]))
        info = information_matrix(sens, weight)
        if not names:
            converged, reason = True, "no free parameters"
            break
        if step_history and step_history[-1] < step_tol:
            converged, reason = True, f"parameter change below {step_tol:g} standard errors"
            break
        if len(cost_history) > 1 and abs(cost_history[-1] - cost_history[-2]) < cost_tol:
            converged, reason = True, f"ML cost change below {cost_tol:g}"
            break
        if iterations >= max_iterations:
            break
        descent = sens.reshape(-1, sens.shape[2]).T @ (v @ weight).reshape(-1)
        step = damped_newton_step(theta, info, concentrated_hessian(sens, v, weight, info, full),
                                  descent, cost_history[-1], trial_cost, lam, step_tol)
        iterations += 1
        if not step.accepted:
            converged, reason = step.at_minimum, step.reason
            break
        with np.errstate(divide="ignore", invalid="ignore"):  # a fixed parameter: std 0
            step_history.append(float(np.max(np.abs(step.theta - theta) / step.std)))
        theta = step.theta
        lam = step.lam
    return MaximumLikelihoodFit(names, dict(zip(names, theta, strict=True)), y, sens, v, noise,
                                info, converged, reason, iterations, cost_history, step_history)
