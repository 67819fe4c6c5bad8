"""Fourier transforms of sampled signals at chosen frequencies: the chirp z-transform on a
uniform grid, a direct transform otherwise, and the finite Fourier transform with cubic
end corrections (Morelli & Klein 2016 sec. 7.1; Filon quadrature).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import czt


def _is_uniform(frequencies: np.ndarray) -> bool:
    if frequencies.size < 3:
        return False
    step = np.diff(frequencies)
    return bool(np.allclose(step, step[0], rtol=1e-9, atol=1e-12 * abs(frequencies[-1])))


def discrete_fourier(x: np.ndarray, dt: float, frequencies: np.ndarray) -> np.ndarray:
    """sum_k x_k exp(-j 2 pi f k dt) along axis 0 at any frequencies; no dt factor.

    A uniform grid goes through the chirp z-transform (scipy.signal.czt, Rabiner et al.
    1969), any other grid through a direct transform.

    Parameters
    ----------
    x : numpy.ndarray
        Samples, time along axis 0; shape (N,) or (N, k).
    dt : float
        Sample interval, s.
    frequencies : numpy.ndarray
        Frequencies, Hz; shape (n_f,).

    Returns
    -------
    numpy.ndarray
        The complex sums, unit of x; shape (n_f,) or (n_f, k).
    """
    x = np.asarray(x)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if _is_uniform(f):
        step = f[1] - f[0]
        w = np.exp(-2j * np.pi * step * dt)
        a = np.exp(2j * np.pi * f[0] * dt)
        return czt(x, m=f.size, w=w, a=a, axis=0)
    k = np.arange(x.shape[0])
    kernel = np.exp(-2j * np.pi * np.outer(f, k) * dt)
    return kernel @ x


def _filon_cubic(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Correction factor W and endpoint weights alpha_0..3 of the cubic-interpolation
    Fourier integral for the kernel exp(-j theta k) (Press et al. 1992, sec. 13.9,
    eqs. 13.9.13-14; Morelli & Klein 2016, sec. 7.2 high-accuracy Fourier transform)."""
    th = np.asarray(theta, dtype=float)
    w = np.empty(th.shape)
    alpha = np.empty(th.shape + (4,), dtype=complex)
    small = np.abs(th) < 0.1
    t = th[small]
    t2, t4, t6 = t * t, t**4, t**6
    w[small] = 1 - 11 / 720 * t4 + 23 / 15120 * t6
    alpha[small, 0] = (-2 / 3 + t2 / 45 + 103 / 15120 * t4 - 169 / 226800 * t6) + 1j * t * (
        2 / 45 + 2 / 105 * t2 - 8 / 2835 * t4 + 86 / 467775 * t6)
    alpha[small, 1] = (7 / 24 - 7 / 180 * t2 + 5 / 3456 * t4 - 7 / 259200 * t6) + 1j * t * (
        7 / 72 - t2 / 168 + 11 / 72576 * t4 - 13 / 5987520 * t6)
    alpha[small, 2] = (-1 / 6 + t2 / 45 - 5 / 6048 * t4 + t6 / 64800) + 1j * t * (
        -7 / 90 + t2 / 210 - 11 / 90720 * t4 + 13 / 7484400 * t6)
    alpha[small, 3] = (1 / 24 - t2 / 180 + 5 / 24192 * t4 - t6 / 259200) + 1j * t * (
        7 / 360 - t2 / 840 + 11 / 362880 * t4 - 13 / 29937600 * t6)
    t = th[~small]
    t2, t4 = t * t, t**4
    c, s, c2, s2 = np.cos(t), np.sin(t), np.cos(2 * t), np.sin(2 * t)
    sp = 6 + t2
    w[~small] = sp / (3 * t4) * (3 - 4 * c + c2)
    alpha[~small, 0] = ((-42 + 5 * t2) + sp * (8 * c - c2)) / (6 * t4) + 1j * (
        (-12 * t + 6 * t * t2) + sp * s2) / (6 * t4)
    alpha[~small, 1] = (14 * (3 - t2) - 7 * sp * c) / (6 * t4) + 1j * (30 * t - 5 * sp * s) / (
        6 * t4)
    alpha[~small, 2] = (-4 * (3 - t2) + 2 * sp * c) / (3 * t4) + 1j * (-12 * t + 2 * sp * s) / (
        3 * t4)
    alpha[~small, 3] = (2 * (3 - t2) - sp * c) / (6 * t4) + 1j * (6 * t - sp * s) / (6 * t4)
    # Press et al. write the kernel exp(+j theta k); ours is exp(-j theta k)
    return w, np.conj(alpha)


def finite_fourier_transform(
    x: np.ndarray, dt: float, frequencies: np.ndarray, *, correct: bool = True
) -> np.ndarray:
    """Finite Fourier integral int_0^T x(t) exp(-j 2 pi f t) dt of uniformly sampled data.

    With ``correct`` the samples are interpolated by cubics and the integral is exact for
    them (multiplicative and endpoint corrections, Press et al. 1992 sec. 13.9; Morelli &
    Klein 2016 sec. 7.2, SIDPAC ``fint``); without, it is the plain Euler sum
    dt * sum x_k exp(-j w t_k).

    Parameters
    ----------
    x : numpy.ndarray
        Samples from t = 0, time along axis 0; shape (N,) or (N, k), N >= 8.
    dt : float
        Sample interval, s.
    frequencies : numpy.ndarray
        Frequencies, Hz (f dt <= 1/2); shape (n_f,).
    correct : bool, optional
        Apply the cubic-interpolation corrections. Default True.

    Returns
    -------
    numpy.ndarray
        The transform, unit(x) * s; shape (n_f,) or (n_f, k).

    Raises
    ------
    ValueError
        For fewer than 8 samples, a non-positive ``dt`` or a frequency above Nyquist.
    """
    x = np.asarray(x, dtype=float)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    if x.shape[0] < 8:
        raise ValueError(f"need at least 8 samples for the Fourier integral, got {x.shape[0]}")
    if dt <= 0:
        raise ValueError(f"sample interval must be positive, got {dt}")
    theta = 2 * np.pi * f * dt
    if np.any(np.abs(theta) > np.pi):
        raise ValueError(
            f"frequencies above the Nyquist frequency {0.5 / dt:g} Hz: max {f.max():g} Hz"
        )
    raw = discrete_fourier(x, dt, f)
    if not correct:
        return dt * raw
    w, alpha = _filon_cubic(theta)
    n = x.shape[0]
    t_end = (n - 1) * dt
    shape = (-1,) + (1,) * (x.ndim - 1)
    head = np.tensordot(alpha, x[:4], axes=([1], [0]))
    tail = np.tensordot(np.conj(alpha), x[::-1][:4], axes=([1], [0]))
    end = head + np.exp(-2j * np.pi * f * t_end).reshape(shape) * tail
    return dt * (w.reshape(shape) * raw + end)


