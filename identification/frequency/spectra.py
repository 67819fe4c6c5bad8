"""Auto and cross spectra averaged over overlapped, tapered segments (Welch 1967; Tischler &
Remple 2012 ch. 7), with the effective number of independent averages.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.frequency.fourier import discrete_fourier

TAPERS = ("hann", "hamming", "rectangular")


@dataclass
class Spectra:
    """Averaged one-sided auto and cross spectra of several channels.

    ``matrix[f, i, j]`` = G_ij(f) = 2/(n U T_w) sum_segments conj(X_i) X_j (unit_i*unit_j/Hz).
    """

    frequency: np.ndarray
    matrix: np.ndarray
    n_segments: int
    n_averages: float  # effective number of independent averages (Welch 1967)
    window: float  # s


def _taper(name: str, n: int) -> np.ndarray:
    if name == "hann":
        return np.hanning(n + 2)[1:-1]  # nonzero end points: every sample contributes
    if name == "hamming":
        return np.hamming(n)
    if name == "rectangular":
        return np.ones(n)
    raise ValueError(f"unknown taper {name!r}; use one of {', '.join(TAPERS)}")


def effective_averages(taper: np.ndarray, n_segments: int, step: int) -> float:
    """Number of independent averages equivalent to overlapped tapered segments.

    Welch (1967) eq. 11 for the variance of an averaged periodogram of white data:
    1/n_eff = (1/K) [1 + 2 sum_{j=1}^{K-1} (1 - j/K) rho(j)^2],
    rho(j) = sum w(k) w(k + j S) / sum w(k)^2, with K segments offset by S samples.

    Parameters
    ----------
    taper : numpy.ndarray
        The segment taper w; shape (segment samples,).
    n_segments : int
        K, the segments averaged.
    step : int
        S, the offset between segments, samples.

    Returns
    -------
    float
        n_eff, 1.
    """
    k = n_segments
    if k <= 1:
        return float(k)
    energy = float(np.sum(taper**2))
    total = 1.0
    for j in range(1, k):
        lag = j * step
        if lag >= taper.size:
            break
        rho = float(np.sum(taper[: taper.size - lag] * taper[lag:])) / energy
        total += 2.0 * (1.0 - j / k) * rho**2
    return k / total


def cross_spectra(
    signals: np.ndarray,
    dt: float,
    window: float,
    frequencies: np.ndarray,
    *,
    overlap: float = 0.5,
    taper: str = "hann",
) -> Spectra:
    """Averaged auto and cross spectra of the columns of ``signals``.

    Each segment's mean is removed.

    Parameters
    ----------
    signals : numpy.ndarray
        Signals, time along axis 0; shape (N,) or (N, k).
    dt : float
        Sample interval, s.
    window : float
        Segment length, s (at least 8 samples, at most the record).
    frequencies : numpy.ndarray
        Frequencies, Hz.
    overlap : float, optional
        Fraction shared by neighbouring segments, in [0, 1). Default 0.5.
    taper : str, optional
        "hann", "hamming" or "rectangular". Default "hann".

    Returns
    -------
    Spectra
        The one-sided spectral matrix (unit_i unit_j / Hz; shape (n_f, k, k)) and its
        averaging.

    Raises
    ------
    ValueError
        For non-finite samples, a window too short or too long, or an overlap out of range.
    """
    x = np.asarray(signals, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if not np.all(np.isfinite(x)):
        bad = np.argwhere(~np.isfinite(x))[0]
        raise ValueError(f"signal {bad[1]} is not finite at sample {bad[0]}")
    n_total = x.shape[0]
    n_win = int(round(window / dt))
    if n_win < 8:
        raise ValueError(f"window of {window} s is only {n_win} samples; need at least 8")
    if n_win > n_total:
        raise ValueError(
            f"window of {window} s ({n_win} samples) is longer than the record "
            f"({n_total} samples, {n_total * dt:g} s)"
        )
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap must be in [0, 1), got {overlap}")
    step = max(1, int(round(n_win * (1.0 - overlap))))
    starts = list(range(0, n_total - n_win + 1, step))
    w = _taper(taper, n_win)
    f = np.atleast_1d(np.asarray(frequencies, dtype=float))
    g = np.zeros((f.size, x.shape[1], x.shape[1]), dtype=complex)
    for s in starts:
        seg = x[s : s + n_win]
        seg = (seg - seg.mean(axis=0)) * w[:, None]
        xf = dt * discrete_fourier(seg, dt, f)  # (n_f, k)
        g += np.conj(xf)[:, :, None] * xf[:, None, :]
    scale = 2.0 / (len(starts) * np.mean(w**2) * n_win * dt)
    return Spectra(
        frequency=f,
        matrix=g * scale,
        n_segments=len(starts),
        n_averages=effective_averages(w, len(starts), step),
        window=n_win * dt,
    )


