"""The ``Estimate`` of an output-error maximum-likelihood fit.

Values in the parameters' units (nondimensional derivatives, SI biases and initial
states), standard errors from ``bounds`` (Cramer-Rao, M&K eq. 6.50, or corrected for
colored residuals, M&K eq. 6.54; ``Estimate.std_kind`` says which), fit statistics
(cost N/2 ln det R, noise standard deviations per output, R^2) and the measured and
modelled time histories.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from flightid.identification.engine import identifiability as ident
from flightid.identification.engine.bounds import (
    HC3_POWER,
    output_error_covariance,
    standard_errors,
)
from flightid.identification.engine.gauss_newton import MaximumLikelihoodFit
from flightid.identification.engine.metrics import r_squared_by_output
from flightid.identification.estimate import Estimate


def estimate_from_fit(
    fit: MaximumLikelihoodFit, *, method: str, model: str, time: np.ndarray,
    measured: np.ndarray, output_names: Sequence[str], fixed: Mapping[str, float],
    unidentifiable: Mapping[str, str], colored: bool, full_noise_covariance: bool,
    leverage_power: float = HC3_POWER,
) -> Estimate:
    """The estimate of a finished fit.

    Parameters
    ----------
    fit : MaximumLikelihoodFit
        The finished fit.
    method : str
        The method id.
    model : str
        The model's name.
    time : numpy.ndarray
        Sample times, s; shape (N,).
    measured : numpy.ndarray
        The outputs z, SI units; shape (N, ny).
    output_names : sequence of str
        The outputs' names.
    fixed : mapping of str to float
        The parameters held at their values, parameter units.
    unidentifiable : mapping of str to str
        {name: reason}.
    colored : bool
        Correct the bounds for colored residuals.
    full_noise_covariance : bool
        Whether R had off-diagonal terms (reported).
    leverage_power : float, optional
        The colored-residual bounds' power of (1 - H_f), dimensionless (``bounds``).
        Default HC3's 2.

    Returns
    -------
    Estimate
        Values, standard errors, covariance, per-output series and fit statistics.
    """
    names = fit.names
    cov, std_kind = output_error_covariance(fit.information, fit.sens, fit.residuals,
                                            fit.noise, colored, leverage_power)
    std = standard_errors(cov)
    outputs = {
        name: {"measured": measured[:, j], "model": fit.y[:, j],
               "residual": fit.residuals[:, j]}
        for j, name in enumerate(output_names)
    }
    r2 = r_squared_by_output(measured, fit.residuals, output_names)
    fit_stats = {
        "model": model,
        "converged": fit.converged,
        "reason": fit.reason,
        "iterations": fit.iterations,
        "cost_history": list(fit.cost_history),
        "step_history": list(fit.step_history),
        "cost": fit.cost_history[-1],
        "noise_std": {o: float(np.sqrt(fit.noise[j, j])) for j, o in enumerate(output_names)},
        "noise_covariance": fit.noise,
        "R2_per_output": r2,
        "R2": float(np.nanmean(list(r2.values()))),
        "fixed": {n: float(v) for n, v in fixed.items()},
        "samples": int(measured.shape[0]),
        "high_correlations": ident.high_correlations(names, cov, 0.9) if names else [],
        "full_noise_covariance": full_noise_covariance,
    }
    return Estimate(
        method=method,
        names=list(names),
        values=np.array([fit.values[n] for n in names]),
        std=std,
        covariance=cov,
        fit=fit_stats,
        unidentifiable=dict(unidentifiable),
        outputs=outputs,
        time=time.copy(),
        std_kind=std_kind,
    )
