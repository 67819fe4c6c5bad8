"""The skeleton every output-error problem shares: the measured outputs on a uniform time
grid, the parameters held fixed, the estimated initial states and the noise-variance floor;
the Gauss-Newton fit of such a problem and the search for its unidentifiable parameters.

A method's problem (``methods.output_error``: a linear model; ``methods.nonlinear_6dof``:
the 6-DOF equations; ``compatibility``: the kinematic equations) extends ``Problem`` with
its model and inputs and hands ``fit`` its two functions of the parameter values
(Morelli & Klein 2016, ch. 6; Jategaonkar 2015, ch. 4).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit, maximum_likelihood


@dataclass(kw_only=True)
class Problem:
    """The data of one output-error fit that every model shares.

    ``time`` (N,) in s on a uniform grid of step ``dt`` (s); ``z`` (N, ny) the measured
    outputs (SI); ``noise_floor`` (ny,) the smallest admitted noise variance per output
    (``noise_floor``); ``fixed`` every parameter not estimated, at its value;
    ``x0_names`` the estimated initial states, ``x0_<state>``.
    """

    time: np.ndarray
    dt: float
    z: np.ndarray
    noise_floor: np.ndarray
    fixed: dict[str, float] = field(default_factory=dict)
    x0_names: tuple[str, ...] = ()


def noise_floor(z: np.ndarray) -> np.ndarray:
    """The smallest noise variance admitted per output: the rounding level of each output.

    Parameters
    ----------
    z : numpy.ndarray
        (N, ny) measured outputs, SI units.

    Returns
    -------
    numpy.ndarray
        (ny,) variances in the outputs' units squared: (1e-10 of the larger of the
        output's range and its largest magnitude, plus 1e-300) squared.
    """
    return (1e-10 * np.maximum(np.ptp(z, axis=0), np.abs(z).max(axis=0)) + 1e-300) ** 2


def fit(problem: Problem,
        outputs_and_sensitivities: Callable[[dict[str, float]], tuple[np.ndarray, np.ndarray]],
        outputs: Callable[[dict[str, float]], np.ndarray], names: list[str],
        values: Mapping[str, float], max_iterations: int, full: bool, step_tol: float,
        cost_tol: float) -> MaximumLikelihoodFit:
    """``gauss_newton.maximum_likelihood`` on a problem's measured outputs and noise floor.

    Parameters
    ----------
    problem : Problem
        The measured outputs ``z`` and the noise floor.
    outputs_and_sensitivities, outputs : callable
        The model's outputs (N, ny) with their sensitivities (N, ny, len(names)), and
        the outputs alone, as functions of {name: value}.
    names : list of str
        The parameters estimated; ``values`` holds their start values.
    values : mapping of str to float
        Start values (nondimensional derivatives, SI biases and states).
    max_iterations : int
        Gauss-Newton iteration limit.
    full : bool
        Estimate the full output-noise covariance (else its diagonal).
    step_tol, cost_tol : float
        Converged when no parameter moved by more than ``step_tol`` standard errors, or
        the cost changed by less than ``cost_tol``.

    Returns
    -------
    MaximumLikelihoodFit
        The fit: values, information matrix, residuals, noise covariance, convergence.
    """
    return maximum_likelihood(problem.z, problem.noise_floor, outputs_and_sensitivities,
                              outputs, names, values, max_iterations, full, step_tol,
                              cost_tol)


def singular(names: list[str], fitted: MaximumLikelihoodFit, tolerance: float,
             keep: Sequence[str]) -> dict[str, str]:
    """The parameters a fit cannot determine (``identifiability.unidentifiable``).

    Parameters
    ----------
    names : list of str
        The parameters estimated, in the order of the fit's information matrix.
    fitted : MaximumLikelihoodFit
        The fit.
    tolerance : float
        The eigenvalue below which the normalised information matrix is singular.
    keep : sequence of str
        Parameters kept in preference when one of a collinear group must go (biases,
        initial states).

    Returns
    -------
    dict of str to str
        Each unidentifiable parameter with the reason.
    """
    values = np.array([fitted.values[n] for n in names])
    return ident.unidentifiable(names, fitted.information, values, prefer_keep=list(keep),
                                tolerance=tolerance)
