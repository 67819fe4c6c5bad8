"""Cramer-Rao bounds of maximum-likelihood estimates, with the colored-residual correction.

The parameter covariance of an efficient estimate is the inverse of the Fisher information
matrix, cov = M^-1 with M = sum_i S_i^T R^-1 S_i, and the standard errors (Cramer-Rao
bounds) are sqrt(diag M^-1) in the units of each parameter (Morelli & Klein 2016, eq. 6.50;
Jategaonkar 2015, ch. 4). Real residuals are colored (model error, turbulence) and
M^-1 then understates the scatter; ``colored_residual_covariance`` is the correction of
M&K eq. 6.54 (SIDPAC ``m_colores``), with the share of each frequency the fit removed put
back (a leverage correction; see its docstring).
"""

from __future__ import annotations

import numpy as np

from flightid.identification.estimate import StdKind

MAX_LEVERAGE = 0.95  # cap of a frequency bin's removed share
HC3_POWER = 2.0  # (1 - H_f)^2: the jackknife form (MacKinnon & White 1985)
# the power of (1 - H_f) for output error's lateral model, between HC2 (1) and HC3 (2):
# measured on development flights of two cards, one in calm air and one in turbulence
# (docs/validation.md, "Choosing the leverage correction"); the longitudinal models keep
# HC3, which the same measurement found not too large for them
LATERAL_LEVERAGE_POWER = 1.5


def cramer_rao_covariance(information: np.ndarray) -> np.ndarray:
    """Parameter covariance M^-1 (M&K eq. 6.50), in parameter units squared.

    Parameters
    ----------
    information : numpy.ndarray
        The Fisher information matrix M, 1 / (parameter unit)^2; shape (np, np).

    Returns
    -------
    numpy.ndarray
        The covariance, parameter units squared; shape (np, np).
    """
    return np.linalg.inv(information)


def colored_residual_covariance(
    sens: np.ndarray, residuals: np.ndarray, weight: np.ndarray, information: np.ndarray,
    leverage: bool = True, power: float = HC3_POWER,
) -> np.ndarray:
    """Parameter covariance corrected for colored residuals (M&K eq. 6.54, SIDPAC m_colores),
    with each frequency's residual power restored for what the fit took out of it.

    M&K eq. 6.54 is M^-1 [sum_i sum_j S_i^T W R_vv(i-j) W S_j] M^-1 with the sample
    autocorrelation R_vv over all lags, computed here in the frequency domain (FFTs of
    length L >= 2N - 1, so the circular correlation equals the linear one) on the whitened
    sensitivities A = W^(1/2) S and residuals e = W^(1/2) v:
    (1/(L N)) sum_f |e_f^H A_f|^2.

    The residuals of a fit are (I - P) v, P the projection on A, and in the frequency domain
    the fit removes from bin f the share H_f = A_f M^-1 A_f^H / N (ny x ny; the shares sum to
    the number of parameters). Where the sensitivities and a colored residual share the same
    low band (a flight in turbulence) the sample spectrum is depleted exactly where the bound
    needs it: the plain eq. 6.54 bounds of output error on the Navion demo card in light
    turbulence are 1.3-2.1 times too small (coverage of the 95 % intervals 57-87 %). With
    ``leverage`` each bin's whitened residual power is therefore divided by
    (I - H_f)^``power``, H_f capped at ``MAX_LEVERAGE``: the frequency-domain form of the
    sandwich corrections of MacKinnon & White (1985), HC2 for ``power`` 1 (unbiased when the
    residual is white across the bins a parameter mixes) and HC3 for 2 (the jackknife form,
    recommended for small samples by Long & Ervin 2000, conservative for white errors). The
    default is HC3; output error's lateral model uses ``LATERAL_LEVERAGE_POWER``
    (``leverage_power``; docs/validation.md, "Choosing the leverage correction").

    Parameters
    ----------
    sens : numpy.ndarray
        Output sensitivities dy/dtheta, output unit per parameter unit; shape (N, ny, np).
    residuals : numpy.ndarray
        Output residuals v, output units; shape (N, ny).
    weight : numpy.ndarray
        W = R^-1, 1 / (output unit)^2; shape (ny, ny).
    information : numpy.ndarray
        The information matrix M; shape (np, np).
    leverage : bool, optional
        Restore each bin's residual power for the fit's share. Default True.
    power : float, optional
        The power of (I - H_f) dividing each bin's residual power, dimensionless, >= 0;
        unused without ``leverage``. Default HC3's 2.

    Returns
    -------
    numpy.ndarray
        The covariance, parameter units squared; shape (np, np).
    """
    n = residuals.shape[0]
    size = int(2 ** np.ceil(np.log2(2 * n)))
    root = np.linalg.cholesky(weight).T  # W = root^T root
    fa = np.fft.rfft(np.matmul(root, sens), n=size, axis=0)  # (F, ny, p)
    fe = np.fft.rfft(residuals @ root.T, n=size, axis=0)[:, :, None]  # (F, ny, 1)
    inv = np.linalg.inv(information)
    if leverage:
        h = (fa @ inv) @ np.conj(np.swapaxes(fa, 1, 2)) / n  # (F, ny, ny), Hermitian
        vals, vecs = np.linalg.eigh(h)
        keep = (1.0 - np.clip(vals, 0.0, MAX_LEVERAGE)) ** (-0.5 * power)
        fe = vecs @ (keep[:, :, None] * (np.conj(np.swapaxes(vecs, 1, 2)) @ fe))
    w = (np.conj(np.swapaxes(fe, 1, 2)) @ fa)[:, 0, :]  # (F, p): e_f^H A_f
    # rfft keeps f = 0 .. L/2: every other bin stands for itself and its mirror image
    factor = np.full(w.shape[0], 2.0)
    factor[0] = 1.0
    if size % 2 == 0:
        factor[-1] = 1.0
    middle = (np.conj(w).T @ (factor[:, None] * w)).real / (size * n)
    cov = inv @ middle @ inv
    return 0.5 * (cov + cov.T)


def leverage_power(model: str) -> float:
    """The power of (1 - H_f) in ``colored_residual_covariance`` for an output-error fit.

    ``LATERAL_LEVERAGE_POWER`` for the linear lateral model (where it was measured), HC3's 2
    for every other.

    Parameters
    ----------
    model : str
        The model's name (``Model.name``, e.g. "lateral").

    Returns
    -------
    float
        The power, dimensionless.
    """
    return LATERAL_LEVERAGE_POWER if model == "lateral" else HC3_POWER


def output_error_covariance(information: np.ndarray, sens: np.ndarray,
                            residuals: np.ndarray, noise: np.ndarray,
                            colored: bool, power: float = HC3_POWER,
                            ) -> tuple[np.ndarray, StdKind]:
    """(covariance, std_kind) of an output-error fit.

    M^-1, or the colored-residual correction (M&K eq. 6.54) when ``colored``; an empty matrix
    when nothing was estimated.

    Parameters
    ----------
    information : numpy.ndarray
        The information matrix M; shape (np, np).
    sens : numpy.ndarray
        Output sensitivities of the fit; shape (N, ny, np).
    residuals : numpy.ndarray
        Output residuals of the fit, output units; shape (N, ny).
    noise : numpy.ndarray
        The noise covariance R, output units squared; shape (ny, ny).
    colored : bool
        Correct for colored residuals.
    power : float, optional
        The leverage correction's power (``colored_residual_covariance``). Default HC3's 2.

    Returns
    -------
    tuple of (numpy.ndarray, StdKind)
        The covariance (parameter units squared, shape (np, np)) and what its standard errors
        are.
    """
    if information.shape[0] == 0:
        return np.zeros((0, 0)), StdKind.NONE
    if colored:
        weight = np.linalg.inv(noise)
        return (colored_residual_covariance(sens, residuals, weight, information,
                                            power=power),
                StdKind.CRAMER_RAO_COLORED)
    return cramer_rao_covariance(information), StdKind.CRAMER_RAO


def standard_errors(covariance: np.ndarray) -> np.ndarray:
    """Standard errors sqrt(diag cov), negative rounding clipped to 0.

    Parameters
    ----------
    covariance : numpy.ndarray
        Parameter covariance, parameter units squared; shape (np, np).

    Returns
    -------
    numpy.ndarray
        Standard errors, parameter units; shape (np,).
    """
    return np.sqrt(np.clip(np.diag(covariance), 0.0, None))
