"""Cramer-Rao bounds of maximum-likelihood estimates, with the colored-residual correction.

The parameter covariance of an efficient estimate is the inverse of the Fisher information
matrix, cov = M^-1 with M = sum_i S_i^T R^-1 S_i, and the standard errors (Cramer-Rao
bounds) are sqrt(diag M^-1) in the units of each parameter (Morelli & Klein 2016, eq. 6.50;
Jategaonkar 2015, ch. 4). Real residuals are colored (model error, turbulence) and
M^-1 then understates the scatter; ``colored_residual_covariance`` is the correction of
M&K eq. 6.54 (SIDPAC ``m_colores``).
"""

from __future__ import annotations

import numpy as np

from flightid.identification.estimate import StdKind


def cramer_rao_covariance(information: np.ndarray) -> np.ndarray:
    """Parameter covariance M^-1 (M&K eq. 6.50), in parameter units squared."""
    return np.linalg.inv(information)


def colored_residual_covariance(
    sens: np.ndarray, residuals: np.ndarray, weight: np.ndarray, information: np.ndarray
) -> np.ndarray:
    """Parameter covariance corrected for colored residuals (M&K eq. 6.54, SIDPAC m_colores).

    M^-1 [sum_i sum_j S_i^T W R_vv(i-j) W S_j] M^-1 with the sample autocorrelation R_vv
    over all lags, computed as (1/(L N)) sum_f w_f^H w_f with w_f = V_f^H (W S)_f (FFTs of
    length L >= 2N - 1, so the circular correlation equals the linear one). ``sens``
    (N, ny, np), ``residuals`` (N, ny), ``weight`` W = R^-1, ``information`` M; the result
    is in parameter units squared.
    """
    n = residuals.shape[0]
    size = int(2 ** np.ceil(np.log2(2 * n)))
    ws = np.einsum("ab,ibk->iak", weight, sens)
    fs = np.fft.rfft(ws, n=size, axis=0)
    fv = np.fft.rfft(residuals, n=size, axis=0)
    w = np.einsum("fa,fak->fk", fv.conj(), fs)
    power = (w.conj()[:, :, None] * w[:, None, :]).real
    # rfft keeps f = 0 .. L/2: every other bin stands for itself and its mirror image
    factor = np.full(power.shape[0], 2.0)
    factor[0] = 1.0
    if size % 2 == 0:
        factor[-1] = 1.0
    middle = np.einsum("f,fjk->jk", factor, power) / (size * n)
    inv = np.linalg.inv(information)
    cov = inv @ middle @ inv
    return 0.5 * (cov + cov.T)


def output_error_covariance(information: np.ndarray, sens: np.ndarray,
                            residuals: np.ndarray, noise: np.ndarray,
                            colored: bool) -> tuple[np.ndarray, StdKind]:
    """(covariance, std_kind) of an output-error fit: M^-1, or the colored-residual
    correction (M&K eq. 6.54) when ``colored``; an empty matrix when nothing was estimated.

    ``sens`` (N, ny, np), ``residuals`` (N, ny) and ``noise`` R (ny, ny) of the fit.
    """
    if information.shape[0] == 0:
        return np.zeros((0, 0)), StdKind.NONE
    if colored:
        weight = np.linalg.inv(noise)
        return (colored_residual_covariance(sens, residuals, weight, information),
                StdKind.CRAMER_RAO_COLORED)
    return cramer_rao_covariance(information), StdKind.CRAMER_RAO


def standard_errors(covariance: np.ndarray) -> np.ndarray:
    """Standard errors sqrt(diag cov) (parameter units), negative rounding clipped to 0."""
    return np.sqrt(np.clip(np.diag(covariance), 0.0, None))
