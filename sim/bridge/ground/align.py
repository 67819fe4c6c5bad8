"""Clock alignment of separately clocked recorders (IMU, input and secondary, as on the
Monash Boomerang 60 UAV, c. 2008).

Each recorder stamps its data with its own clock, t_src = offset + (1 + drift) t_ref,
against the reference recorder's clock t_ref. Two ways to find offset and drift:
- time sync: recorders that also log a common time (SYSTEM_TIME pairs GPS/unix time with
  the recorder's boot time) give both clocks as straight lines in the common time; a
  least-squares line per recorder and their composition give offset and drift;
- cross-correlation of a signal both recorders measure (a servo position, a rate): the
  lag of the correlation peak of the signals' first differences (differencing whitens
  slow signals and sharpens the peak) gives the offset to a few ms; offset, drift and a
  constant bias are then refined by least squares, the source samples against the
  interpolated reference (the output-error estimate of a time shift, as in the data
  compatibility analysis of Morelli & Klein 2016 and Jategaonkar 2015).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares


@dataclass(frozen=True)
class ClockMap:
    """t_src = offset + (1 + drift) t_ref; how it was found and how well."""

    offset: float = 0.0  # s
    drift: float = 0.0  # fraction
    method: str = "reference"
    via: str = ""  # the common signal or stream used
    sigma: float = 0.0  # standard error of the offset (s), white-residual assumption

    def to_reference(self, t_src: np.ndarray) -> np.ndarray:
        """Source clock times (s) on the reference clock (s)."""
        return (np.asarray(t_src, dtype=float) - self.offset) / (1.0 + self.drift)

    def then(self, other: ClockMap) -> ClockMap:
        """Compose: self maps A -> B (t_A = f(t_B)), other maps B -> ref; result A -> ref."""
        # t_A = o1 + (1+d1) t_B,  t_B = o2 + (1+d2) t_ref
        return ClockMap(
            self.offset + (1 + self.drift) * other.offset,
            (1 + self.drift) * (1 + other.drift) - 1,
            f"{self.method}+{other.method}", f"{self.via} / {other.via}",
            float(np.hypot(self.sigma, other.sigma)),
        )

    def as_dict(self) -> dict:
        """Plain data, drift in ppm."""
        return {"offset_s": self.offset, "drift_ppm": self.drift * 1e6, "method": self.method,
                "via": self.via, "sigma_offset_s": self.sigma}


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares y = a + b x; returns a, b and the residual rms."""
    A = np.column_stack([np.ones_like(x), x])
    (a, b), *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - (a + b * x)
    return float(a), float(b), float(np.sqrt(np.mean(res**2))) if res.size else 0.0


def timesync_map(
    src_common: np.ndarray, src_local: np.ndarray,
    ref_common: np.ndarray, ref_local: np.ndarray,
) -> ClockMap:
    """Clock map from (common time, local time) pairs of a source and the reference.

    Parameters
    ----------
    src_common, src_local : numpy.ndarray
        The source's time-sync pairs: common (unix) time and local clock time, s.
    ref_common, ref_local : numpy.ndarray
        The reference's time-sync pairs, s.

    Returns
    -------
    ClockMap
        t_src = offset + (1 + drift) t_ref, with the offset's standard error (s).

    Raises
    ------
    ValueError
        When a stream has fewer than two pairs or unequal lengths.
    """
    for name, c, loc in (("source", src_common, src_local), ("reference", ref_common, ref_local)):
        if len(c) < 2 or np.ptp(c) <= 0:
            raise ValueError(f"time sync: the {name} stream has fewer than two time-sync pairs")
        if len(c) != len(loc):
            raise ValueError(f"time sync: {name} has {len(c)} common and {len(loc)} local times")
    u0 = float(np.min(ref_common))
    a_s, b_s, r_s = _line(np.asarray(src_common) - u0, np.asarray(src_local, dtype=float))
    a_r, b_r, r_r = _line(np.asarray(ref_common) - u0, np.asarray(ref_local, dtype=float))
    # t_src = a_s + b_s u, t_ref = a_r + b_r u  =>  t_src = a_s + (b_s/b_r)(t_ref - a_r)
    ratio = b_s / b_r
    sigma = float(np.hypot(r_s / np.sqrt(len(src_common)), r_r / np.sqrt(len(ref_common))))
    return ClockMap(a_s - ratio * a_r, ratio - 1.0, "timesync", "SYSTEM_TIME", sigma)


def _uniform(t: np.ndarray, v: np.ndarray, t0: float, fs: float, n: int) -> np.ndarray:
    return np.interp(t0 + np.arange(n) / fs, t, v)


def _peak(x: np.ndarray, y: np.ndarray, max_shift: int, centre: int = 0) -> tuple[float, float]:
    """Shift s (samples, sub-sample) maximising sum x[k] y[k+s] near ``centre``, and the
    normalised correlation there."""
    x = x - x.mean()
    y = y - y.mean()
    n = len(x)
    best, best_s, corr = -np.inf, 0, []
    shifts = range(centre - max_shift, centre + max_shift + 1)
    for s in shifts:
        if s >= 0:
            a, b = x[: n - s], y[s:]
        else:
            a, b = x[-s:], y[: n + s]
        if len(a) < 8:
            corr.append(-np.inf)
            continue
        den = np.sqrt(np.dot(a, a) * np.dot(b, b))
        c = float(np.dot(a, b) / den) if den > 0 else 0.0
        corr.append(c)
        if c > best:
            best, best_s = c, s
    i = best_s - shifts.start
    frac = 0.0
    if 0 < i < len(corr) - 1 and np.isfinite(corr[i - 1]) and np.isfinite(corr[i + 1]):
        den = corr[i - 1] - 2 * corr[i] + corr[i + 1]
        if den < 0:
            frac = 0.5 * (corr[i - 1] - corr[i + 1]) / den
    return best_s + frac, best


def xcorr_map(
    ref_t: np.ndarray, ref_v: np.ndarray, src_t: np.ndarray, src_v: np.ndarray,
    *, max_offset: float = 10.0, via: str = "",
) -> ClockMap:
    """Clock map from one signal both recorders measured.

    The source signal is ref(t_ref) seen at t_src = offset + (1 + drift) t_ref (plus a
    constant sensor bias); the offset is searched within +-max_offset s by correlating
    first differences on a 200 Hz grid, then offset, drift and bias are refined by least
    squares on the source samples against the linearly interpolated reference.

    Parameters
    ----------
    ref_t, ref_v : numpy.ndarray
        Reference times (s, its own clock) and values.
    src_t, src_v : numpy.ndarray
        Source times (s, its own clock) and values, same unit as ``ref_v``.
    max_offset : float, optional
        Largest offset searched, s. Default 10.
    via : str, optional
        Names the common signal in the map and in messages.

    Returns
    -------
    ClockMap
        Offset (s), drift (fraction) and the offset's standard error (s).

    Raises
    ------
    ValueError
        With fewer than 16 samples in a stream or no clear correlation peak.
    """
    ref_t, ref_v, src_t, src_v = (np.asarray(a, dtype=float) for a in (ref_t, ref_v, src_t, src_v))
    what = f"cross-correlation{' of ' + via if via else ''}"
    if len(ref_t) < 16 or len(src_t) < 16:
        raise ValueError(f"{what} needs >= 16 samples in both streams")
    fs = 200.0
    lo = min(ref_t[0], src_t[0])
    hi = max(ref_t[-1], src_t[-1])
    n = int((hi - lo) * fs) + 1
    tg = lo + np.arange(n) / fs
    # NaN outside each stream's own span (held values would bias the peak)
    x = np.where((tg >= ref_t[0]) & (tg <= ref_t[-1]), np.interp(tg, ref_t, ref_v), np.nan)
    y = np.where((tg >= src_t[0]) & (tg <= src_t[-1]), np.interp(tg, src_t, src_v), np.nan)
    # correlate first differences: slow trends (heading, speed) would otherwise give broad
    # peaks; differencing whitens the signals and sharpens the peak
    x, y = np.diff(x), np.diff(y)
    x = np.nan_to_num(x - np.nanmean(x))
    y = np.nan_to_num(y - np.nanmean(y))
    shift, peak = _peak_fft(x, y, int(max_offset * fs))
    if peak < 0.5:
        raise ValueError(
            f"{what} found no clear peak (best normalised correlation {peak:.2f} < 0.5): "
            "no common excitation in both streams"
        )
    offset0 = shift / fs

    def residual(theta: np.ndarray) -> np.ndarray:
        offset, drift, bias = theta
        tau = (src_t - offset) / (1.0 + drift)
        inside = (tau >= ref_t[0]) & (tau <= ref_t[-1])
        r = src_v - bias - np.interp(tau, ref_t, ref_v)
        return np.where(inside, r, 0.0)

    bias0 = float(np.median(src_v) - np.median(ref_v))
    fit = least_squares(residual, [offset0, 0.0, bias0], x_scale=[1e-3, 1e-5, 1.0],
                        method="lm")
    offset, drift, _ = fit.x
    if abs(offset - offset0) > 2.0 / fs + 1e-3:
        raise ValueError(f"{what}: the least-squares refinement left the correlation peak "
                         f"({offset0:.4f} s -> {offset:.4f} s)")
    m = int(np.count_nonzero(fit.fun))
    s2 = float(fit.fun @ fit.fun) / max(m - 3, 1)
    try:
        cov = s2 * np.linalg.inv(fit.jac.T @ fit.jac)
        sigma = float(np.sqrt(cov[0, 0]))
    except np.linalg.LinAlgError:
        sigma = float("inf")
    return ClockMap(float(offset), float(drift), "xcorr", via, sigma)


def _peak_fft(x: np.ndarray, y: np.ndarray, max_shift: int) -> tuple[float, float]:
    """Coarse shift (samples, sub-sample) of y against x by FFT correlation, within +-max."""
    n = len(x)
    size = 1 << int(np.ceil(np.log2(2 * n)))
    cc = np.fft.irfft(np.conj(np.fft.rfft(x, size)) * np.fft.rfft(y, size), size)
    shifts = np.concatenate([np.arange(0, max_shift + 1), np.arange(-max_shift, 0)])
    vals = cc[shifts % size]
    # normalise by the overlap energies so that partial overlaps compare fairly
    norm = np.sqrt(np.dot(x, x) * np.dot(y, y))
    vals = vals / norm if norm > 0 else vals
    i = int(np.argmax(vals))
    s = int(shifts[i])
    frac = 0.0
    lo, hi = cc[(s - 1) % size], cc[(s + 1) % size]
    den = lo - 2 * cc[s % size] + hi
    if den < 0:
        frac = 0.5 * (lo - hi) / den
    # refine the normalised peak on the exact overlap
    _, peak = _peak(x, y, 1, centre=s)
    return s + frac, peak
