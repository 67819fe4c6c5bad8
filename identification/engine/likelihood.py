"""The output-error likelihood: noise covariance, concentrated cost, information, Hessian.

For residuals v_i = z_i - y_i(theta) (N samples, ny outputs, SI units of each output) and
Gaussian measurement noise of covariance R, the negative log-likelihood is, up to a
constant, J = 1/2 sum_i v_i^T R^-1 v_i + N/2 ln det R (Morelli & Klein 2016, ch. 6;
Jategaonkar 2015, ch. 4). Its minimum over R is R = 1/N sum v v^T (M&K eq. 6.26), which
leaves the concentrated cost N/2 ln det R (M&K eq. 6.22). The output sensitivities
S_i = dy_i/dtheta (N, ny, np) give the Fisher information matrix M = sum_i S_i^T R^-1 S_i
(M&K eq. 6.33), the Gauss-Newton approximation of the Hessian of J.
"""

from __future__ import annotations

import numpy as np


def noise_covariance(residuals: np.ndarray, full: bool, floor: np.ndarray) -> np.ndarray:
    """Measurement-noise covariance R = 1/N sum v v^T (M&K eq. 6.26), in output units squared.

    The diagonal is kept above ``floor`` so that an output fitted to rounding (noise-free
    simulated data) does not make R singular.

    Parameters
    ----------
    residuals : numpy.ndarray
        Output residuals v, output units; shape (N, ny).
    full : bool
        Keep the off-diagonal terms; else R is diagonal.
    floor : numpy.ndarray
        The smallest variance per output, output units squared; shape (ny,).

    Returns
    -------
    numpy.ndarray
        R, output units squared; shape (ny, ny).
    """
    r = residuals.T @ residuals / residuals.shape[0]
    if not full:
        r = np.diag(np.diag(r))
    r[np.diag_indices_from(r)] = np.maximum(np.diag(r), floor)
    return r


def concentrated_cost(residuals: np.ndarray, full: bool, floor: np.ndarray) -> float:
    """ML cost with R at its optimum for these residuals: N/2 ln det R (M&K eq. 6.22).

    Parameters
    ----------
    residuals : numpy.ndarray
        Output residuals, output units; shape (N, ny).
    full : bool
        R with off-diagonal terms (``noise_covariance``).
    floor : numpy.ndarray
        The smallest variance per output; shape (ny,).

    Returns
    -------
    float
        The cost, nondimensional.
    """
    noise = noise_covariance(residuals, full, floor)
    return 0.5 * residuals.shape[0] * float(np.linalg.slogdet(noise)[1])


def information_matrix(sens: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Fisher information M = sum_i S_i^T W S_i (M&K eq. 6.33).

    A diagonal W takes one matrix product of whitened sensitivities.

    Parameters
    ----------
    sens : numpy.ndarray
        Output sensitivities, output unit per parameter unit; shape (N, ny, np).
    weight : numpy.ndarray
        W = R^-1, 1 / (output unit)^2; shape (ny, ny).

    Returns
    -------
    numpy.ndarray
        M, 1 / (parameter unit)^2; shape (np, np).
    """
    if np.count_nonzero(weight - np.diag(np.diag(weight))) == 0:
        s = sens * np.sqrt(np.diag(weight))[None, :, None]
        flat = s.reshape(-1, s.shape[2])
        return flat.T @ flat
    return np.einsum("iak,ab,ibl->kl", sens, weight, sens)


def concentrated_hessian(sens: np.ndarray, v: np.ndarray, weight: np.ndarray,
                         info: np.ndarray, full: bool) -> np.ndarray:
    """Newton matrix of the concentrated cost N/2 ln det R(theta).

    The information matrix M minus the term from the dependence of R on theta,
        H_kl = M_kl - 1/(2N) tr(W C_k W C_l),  C_k = B_k + B_k^T,  B_k = sum_i s_ik v_i^T,
    with only the diagonal of C_k when R is diagonal.

    Parameters
    ----------
    sens : numpy.ndarray
        Output sensitivities; shape (N, ny, np).
    v : numpy.ndarray
        Output residuals, output units; shape (N, ny).
    weight : numpy.ndarray
        W = R^-1; shape (ny, ny).
    info : numpy.ndarray
        M from ``information_matrix``; shape (np, np).
    full : bool
        R has off-diagonal terms; False keeps only the diagonal of C_k.

    Returns
    -------
    numpy.ndarray
        H, 1 / (parameter unit)^2; shape (np, np).
    """
    n, ny, k = sens.shape
    b = (sens.transpose(2, 1, 0).reshape(k * ny, n) @ v).reshape(k, ny, ny)
    c = b + b.transpose(0, 2, 1)
    if not full:
        c = np.einsum("kaa->ka", c)  # only the diagonal of R is estimated
        wd = np.diag(weight)
        return info - np.einsum("ka,a,la->kl", c, wd**2, c) / (2 * v.shape[0])
    wc = np.einsum("ab,kbc->kac", weight, c)
    return info - np.einsum("kab,lba->kl", wc, wc) / (2 * v.shape[0])
