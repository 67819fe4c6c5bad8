"""Fit metrics of a model output against the measured one: R^2, Theil's inequality
coefficient and J_rms, used by every method's fit statistics and by the validation.

* R^2 = 1 - SSE / SST, SST the sum of squares about the measured mean (Morelli & Klein
  2016 eq. 5.54).
* Theil inequality coefficient (Theil 1961; Jategaonkar 2015 sec. 11.2):
  TIC = sqrt(mean((y - yhat)^2)) / (sqrt(mean(y^2)) + sqrt(mean(yhat^2))), 0 for a perfect
  match, 1 for no agreement.
* J_rms: the root mean square of the residual, in the unit of y.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def determination(sse: float, sst: float) -> float:
    """The coefficient of determination from its two sums.

    Parameters
    ----------
    sse : float
        The sum of squared residuals (unit of y squared).
    sst : float
        The sum of squares of y about its mean (unit of y squared).

    Returns
    -------
    float
        1 - sse / sst (dimensionless); NaN when y does not vary (sst = 0).
    """
    return 1.0 - sse / sst if sst > 0 else float("nan")


def r_squared(y: np.ndarray, yhat: np.ndarray) -> float:
    """The coefficient of determination of a model output against the measured one.

    Parameters
    ----------
    y, yhat : numpy.ndarray
        The measured and the model output (same shape and unit).

    Returns
    -------
    float
        1 - SSE/SST about the mean of y (dimensionless; NaN when y is constant).
    """
    y, yhat = paired(y, yhat)
    sst = float(np.sum((y - y.mean()) ** 2))
    return determination(float(np.sum((y - yhat) ** 2)), sst)


def r_squared_by_output(measured: np.ndarray, residuals: np.ndarray,
                        names: Sequence[str]) -> dict[str, float]:
    """R^2 of each output of a multi-output fit.

    Parameters
    ----------
    measured : numpy.ndarray
        The measured outputs, (samples, outputs), each in its own unit.
    residuals : numpy.ndarray
        measured - model, same shape and units.
    names : sequence of str
        The outputs' names, one per column.

    Returns
    -------
    dict of str to float
        {output: R^2} (dimensionless; NaN for an output that does not vary).
    """
    spread = np.sum((measured - measured.mean(axis=0)) ** 2, axis=0)
    return {o: float(determination(np.sum(residuals[:, j] ** 2), spread[j]))
            for j, o in enumerate(names)}


def theil_inequality(y: np.ndarray, yhat: np.ndarray) -> float:
    """Theil inequality coefficient of a model output against the measured one.

    Parameters
    ----------
    y, yhat : numpy.ndarray
        The measured and the model output (same shape and unit).

    Returns
    -------
    float
        0 for a perfect match .. 1 for no agreement (dimensionless).
    """
    y, yhat = paired(y, yhat)
    denom = np.sqrt(np.mean(y**2)) + np.sqrt(np.mean(yhat**2))
    if denom == 0:
        return 0.0
    return float(np.sqrt(np.mean((y - yhat) ** 2)) / denom)


def j_rms(y: np.ndarray, yhat: np.ndarray) -> float:
    """Root mean square of the residual.

    Parameters
    ----------
    y, yhat : numpy.ndarray
        The measured and the model output (same shape and unit).

    Returns
    -------
    float
        sqrt(mean((y - yhat)^2)), in the unit of y.
    """
    y, yhat = paired(y, yhat)
    return float(np.sqrt(np.mean((y - yhat) ** 2)))


def paired(y: np.ndarray, yhat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The measured and model outputs as float arrays of one shape, not empty.

    Parameters
    ----------
    y : numpy.ndarray
        Measured outputs.
    yhat : numpy.ndarray
        Model outputs, same shape and units.

    Returns
    -------
    tuple of numpy.ndarray
        ``y`` and ``yhat`` as float arrays.

    Raises
    ------
    ValueError
        When the shapes differ or there are no samples.
    """
    y = np.asarray(y, dtype=float)
    yhat = np.asarray(yhat, dtype=float)
    if y.shape != yhat.shape:
        raise ValueError(f"measured {y.shape} and model {yhat.shape} outputs differ in shape")
    if y.size == 0:
        raise ValueError("no samples to compare")
    return y, yhat
