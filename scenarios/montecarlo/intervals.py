"""Confidence intervals of a study's statistics: the ratio of two scatters (F
distribution for independent samples, a paired bootstrap for samples flown with the same
seeds), one scatter (chi-square) and a coverage (Clopper-Pearson binomial).

A scatter is a sample standard deviation s of n normal errors: (n - 1) s^2 / sigma^2 is
chi-square with n - 1 degrees of freedom, and for two independent samples
(s_a^2 / s_b^2) / (sigma_a^2 / sigma_b^2) is F(n_a - 1, n_b - 1) (Montgomery & Runger,
Applied Statistics and Probability for Engineers, 2014, 8-4 and 10-5). A coverage is a
binomial share k / n; its exact interval is that of Clopper & Pearson (1934, Biometrika
26, 404-413), from the beta distribution. Two designs flown with the same seeds share
their turbulence and noise, so their errors correlate and the F interval is conservative;
resampling the realizations as pairs keeps that correlation (Efron & Tibshirani, An
Introduction to the Bootstrap, 1993, ch. 13, percentile interval).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

LEVEL = 0.90  # the confidence of the intervals reported with scatter ratios
PAIRED_MIN = 20  # fewer pairs: the percentile bootstrap is too narrow, the F interval is used
BOOTSTRAP_DRAWS = 4000


def _alpha(level: float) -> float:
    if not 0.0 < level < 1.0:
        raise ValueError(f"confidence level must be in (0, 1), got {level}")
    return 1.0 - level


def scatter_ratio_interval(ratio: float, n_a: int, n_b: int,
                           level: float = LEVEL) -> tuple[float, float]:
    """The ``level`` interval of sigma_a / sigma_b given the ratio of sample standard
    deviations s_a / s_b = ``ratio`` (n_a and n_b errors each): ratio / sqrt(F_hi) to
    ratio / sqrt(F_lo), with F_lo and F_hi the (1 -+ level) / 2 quantiles of
    F(n_a - 1, n_b - 1). (NaN, NaN) when either n is below 2 or the ratio is not finite.
    The samples are taken as independent; with the same seeds for both (common random
    numbers) the errors correlate positively and the interval is conservative.

    Parameters
    ----------
    ratio : float
        s_a / s_b, 1.
    n_a, n_b : int
        Number of errors behind s_a and s_b.
    level : float, optional
        Confidence level, 0..1.

    Returns
    -------
    tuple[float, float]
        (low, high), 1.
    """
    alpha = _alpha(level)
    if n_a < 2 or n_b < 2 or not math.isfinite(ratio) or ratio < 0:
        return math.nan, math.nan
    f = stats.f(n_a - 1, n_b - 1)
    return (ratio / math.sqrt(f.ppf(1 - alpha / 2)), ratio / math.sqrt(f.ppf(alpha / 2)))


def scatter_interval(scatter: float, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The ``level`` interval of sigma given a sample standard deviation ``scatter`` of
    ``n`` normal errors: scatter sqrt((n - 1) / chi2_hi) to scatter sqrt((n - 1) / chi2_lo)
    (same units as ``scatter``); (NaN, NaN) for n below 2.

    Parameters
    ----------
    scatter : float
        Sample standard deviation.
    n : int
        Number of errors.
    level : float, optional
        Confidence level, 0..1.

    Returns
    -------
    tuple[float, float]
        (low, high).
    """
    alpha = _alpha(level)
    if n < 2 or not math.isfinite(scatter):
        return math.nan, math.nan
    chi2 = stats.chi2(n - 1)
    return (scatter * math.sqrt((n - 1) / chi2.ppf(1 - alpha / 2)),
            scatter * math.sqrt((n - 1) / chi2.ppf(alpha / 2)))


def binomial_interval(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The Clopper-Pearson ``level`` interval of a share from ``k`` successes in ``n``
    trials (fractions 0..1): the alpha/2 quantile of Beta(k, n - k + 1) to the 1 - alpha/2
    quantile of Beta(k + 1, n - k), 0 at k = 0 and 1 at k = n; (NaN, NaN) for n = 0.

    Parameters
    ----------
    k : int
        Successes, 0..n.
    n : int
        Trials.
    level : float, optional
        Confidence level, 0..1. Default 0.95.

    Returns
    -------
    tuple[float, float]
        (low, high), fractions.
    """
    alpha = _alpha(level)
    if n <= 0:
        return math.nan, math.nan
    if not 0 <= k <= n:
        raise ValueError(f"successes must be within 0..{n}, got {k}")
    low = 0.0 if k == 0 else float(stats.beta.ppf(alpha / 2, k, n - k + 1))
    high = 1.0 if k == n else float(stats.beta.ppf(1 - alpha / 2, k + 1, n - k))
    return low, high


def binomial_band(n: int, nominal: float = 0.95, level: float = 0.99) -> tuple[float, float]:
    """The central ``level`` band of the share of successes in ``n`` trials whose true
    share is ``nominal`` (fractions 0..1: the Binomial(n, nominal) quantiles over n): a
    coverage outside it is a warning that the bounds are not what they claim, at the
    false-alarm rate 1 - ``level`` per derivative; (NaN, NaN) for n = 0.

    Parameters
    ----------
    n : int
        Trials.
    nominal : float, optional
        True share, 0..1. Default 0.95.
    level : float, optional
        Probability inside the band, 0..1. Default 0.99.

    Returns
    -------
    tuple[float, float]
        (low, high), fractions.
    """
    if n <= 0:
        return math.nan, math.nan
    low, high = stats.binom.interval(level, n, nominal)
    return float(low) / n, float(high) / n


def paired_ratio_interval(errors_a: np.ndarray, errors_b: np.ndarray, level: float = LEVEL,
                          draws: int = BOOTSTRAP_DRAWS, seed: int = 0
                          ) -> tuple[float, float]:
    """The ``level`` percentile-bootstrap interval of sigma_a / sigma_b from paired errors
    (realization i of both designs flown with the same seed): ``draws`` resamples of the
    pairs, each the ratio of the sample standard deviations (ddof 1); fixed ``seed``, so
    the interval is reproducible. (NaN, NaN) for fewer than PAIRED_MIN pairs.

    Parameters
    ----------
    errors_a, errors_b : numpy.ndarray
        Paired errors of designs a and b; equal shapes (n,).
    level : float, optional
        Confidence level, 0..1.
    draws : int, optional
        Bootstrap resamples.
    seed : int, optional
        Seed of the resampling. Default 0.

    Returns
    -------
    tuple[float, float]
        (low, high), 1.
    """
    alpha = _alpha(level)
    a = np.asarray(errors_a, float)
    b = np.asarray(errors_b, float)
    if a.shape != b.shape:
        raise ValueError(f"paired errors need equal lengths, got {a.size} and {b.size}")
    if a.size < PAIRED_MIN:
        return math.nan, math.nan
    idx = np.random.default_rng(seed).integers(0, a.size, size=(draws, a.size))
    ratios = np.std(a[idx], axis=1, ddof=1) / np.std(b[idx], axis=1, ddof=1)
    low, high = np.quantile(ratios[np.isfinite(ratios)], [alpha / 2, 1 - alpha / 2])
    return float(low), float(high)


def paired_mean_relative_interval(errors_a: np.ndarray, errors_b: np.ndarray,
                                  truth: np.ndarray, level: float = LEVEL,
                                  draws: int = BOOTSTRAP_DRAWS, seed: int = 0,
                                  statistic: str = "scatter"
                                  ) -> tuple[float, float, float]:
    """Design a against b on several derivatives at once: the ratio of the mean over the
    derivatives of scatter / |truth| (``errors_*``: realizations x derivatives, the same
    seeds row by row; ``truth`` non-zero, one per derivative) and its ``level``
    percentile-bootstrap interval, resampling whole realizations as pairs:
    (ratio, low, high); NaN bounds for fewer than PAIRED_MIN realizations.
    ``statistic="mean"``: the mean of each column instead of its scatter (``errors_*``
    then the reported standard errors: the ratio of the mean bound / |truth|).

    Parameters
    ----------
    errors_a, errors_b : numpy.ndarray
        Errors (or standard errors) of designs a and b; shape (realizations, derivatives).
    truth : numpy.ndarray
        True values, non-zero; shape (derivatives,).
    level : float, optional
        Confidence level, 0..1.
    draws : int, optional
        Bootstrap resamples.
    seed : int, optional
        Seed of the resampling. Default 0.
    statistic : str, optional
        ``"scatter"`` (default) or ``"mean"``.

    Returns
    -------
    tuple[float, float, float]
        (ratio, low, high), 1.
    """
    alpha = _alpha(level)
    a = np.asarray(errors_a, float)
    b = np.asarray(errors_b, float)
    scale = 1.0 / np.abs(np.asarray(truth, float))
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] != scale.size:
        raise ValueError(f"paired errors need equal shapes (realizations x {scale.size}), "
                         f"got {a.shape} and {b.shape}")

    if statistic not in ("scatter", "mean"):
        raise ValueError(f"statistic must be 'scatter' or 'mean', got {statistic!r}")

    def column(x: np.ndarray) -> np.ndarray:
        return (np.std(x, axis=-2, ddof=1) if statistic == "scatter"
                else np.mean(x, axis=-2))

    def stat(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return (np.mean(column(x) * scale, axis=-1)
                / np.mean(column(y) * scale, axis=-1))

    ratio = float(stat(a, b))
    if a.shape[0] < PAIRED_MIN:
        return ratio, math.nan, math.nan
    idx = np.random.default_rng(seed).integers(0, a.shape[0], size=(draws, a.shape[0]))
    ratios = stat(a[idx], b[idx])
    low, high = np.quantile(ratios, [alpha / 2, 1 - alpha / 2])
    return ratio, float(low), float(high)


def interval_text(low: float, high: float, digits: int = 3) -> str:
    """``low - high`` with ``digits`` significant digits, trailing zeros kept, and more
    digits (up to 6) for an end that would otherwise read as exactly 1 (parity) while it
    is not, so that the text shows on which side of parity an interval lies; ``-`` for an
    interval that is not defined (NaN).

    Parameters
    ----------
    low, high : float
        The interval's ends.
    digits : int, optional
        Significant digits. Default 3.

    Returns
    -------
    str
        The text.
    """
    def end(x: float) -> str:
        for d in range(digits, 7):
            text = f"{x:#.{d}g}".rstrip(".")
            if float(text) != 1.0 or x == 1.0:
                break
        return text

    if not (np.isfinite(low) and np.isfinite(high)):
        return "-"
    return f"{end(low)} - {end(high)}"
