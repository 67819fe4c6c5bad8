"""Ordinary least squares with Cramer-Rao bounds, optionally corrected for colored residuals.

The covariance correction follows Morelli & Klein 2016, ch. 5 (least squares with
colored residuals), evaluated by FFT convolution (see ``equation_error.estimation``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import fftconvolve

from flightid.identification.engine.metrics import determination


def colored_residual_covariance(x: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Parameter covariance corrected for colored residuals (Morelli & Klein 2016, ch. 5).

    The residual autocorrelation is the biased estimate over all lags.

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    residual : numpy.ndarray
        Equation-error residuals, shape (N,).

    Returns
    -------
    numpy.ndarray
        Covariance, shape (p, p), in the parameters' units squared; symmetric.
    """
    n = residual.size
    rvv = np.correlate(residual, residual, mode="full")[n - 1:] / n if n < 4096 else (
        fftconvolve(residual, residual[::-1], mode="full")[n - 1:] / n
    )
    kernel = np.concatenate([rvv[:0:-1], rvv])  # R(|k|), k = -(n-1) .. n-1
    # (T x)(i) = sum_j R(|i - j|) x(j): a convolution with the symmetric kernel
    tx = fftconvolve(kernel[:, None], x, mode="full", axes=0)[n - 1: 2 * n - 1]
    xtx_inv = np.linalg.inv(x.T @ x)
    middle = x.T @ tx
    cov = xtx_inv @ middle @ xtx_inv
    return 0.5 * (cov + cov.T)


@dataclass
class LeastSquares:
    """Result of one least-squares fit: parameters, covariance and statistics."""

    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    model: np.ndarray
    statistics: dict


def least_squares(x: np.ndarray, y: np.ndarray, colored: bool = True) -> LeastSquares:
    """OLS of y on the columns of x with Cramer-Rao bounds, optionally colored-corrected.

    Parameters
    ----------
    x : numpy.ndarray
        Regressor matrix, shape (N, p).
    y : numpy.ndarray
        Dependent variable, shape (N,).
    colored : bool, optional
        Covariance corrected for colored residuals (default) or plain OLS s^2 (X'X)^-1.

    Returns
    -------
    LeastSquares
        theta (p,), std (p,), covariance (p, p), model (N,) and statistics: R2 (about the
        mean), s2 = SSE/(N - p), F, PSE (Morelli & Klein 5.4), N, n_parameters,
        condition_number, std_kind, std_ols.

    Raises
    ------
    ValueError
        N <= p.
    """
    n, p = x.shape
    if n <= p:
        raise ValueError(f"{n} samples cannot determine {p} parameters")
    theta, *_ = np.linalg.lstsq(x, y, rcond=None)
    model = x @ theta
    v = y - model
    sse = float(v @ v)
    s2 = sse / (n - p)
    xtx_inv = np.linalg.inv(x.T @ x)
    cov_ols = s2 * xtx_inv
    std_ols = np.sqrt(np.diag(cov_ols))
    if colored:
        cov = colored_residual_covariance(x, v)
        kind = "corrected"
    else:
        cov = cov_ols
        kind = "OLS"
    sst = float(np.sum((y - y.mean()) ** 2))
    r2 = determination(sse, sst)
    sigma_max2 = sst / n
    # count the regressors other than a constant column for the F statistic
    has_const = np.any(np.all(np.isclose(x, x[:1]), axis=0))
    k = p - 1 if has_const else p
    f_stat = ((sst - sse) / k) / s2 if k > 0 and s2 > 0 else math.nan
    col_norm = np.linalg.norm(x, axis=0)
    col_norm[col_norm == 0] = 1.0
    cond = float(np.linalg.cond(x / col_norm))
    return LeastSquares(
        theta=theta,
        std=np.sqrt(np.diag(cov)),
        covariance=cov,
        model=model,
        statistics={
            "R2": r2,
            "s2": s2,
            "F": f_stat,
            "PSE": sse / n + sigma_max2 * p / n,
            "N": n,
            "n_parameters": p,
            "condition_number": cond,
            "std_kind": kind,
            "std_ols": std_ols,
        },
    )
