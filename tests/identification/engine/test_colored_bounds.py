"""The colored-residual bounds (identification.engine.bounds) on a problem nobody tuned
them to: a least-squares fit of 8 smooth regressors with an AR(1) residual of the same low
band (phi = 0.95, as turbulence is to a flight's sensitivities), 300 draws.

M&K eq. 6.54 alone (the sample residual spectrum) misses what the fit took out of the
residual in the band the regressors share: measured coverage of the 95 % intervals
72-91 %, scatter 1.16-1.72 times the bound. With each frequency bin's residual restored
by its leverage (the frequency-domain HC3 correction): 94-97 %, ratio 0.81-0.91 (HC3 is
a little conservative). 300 draws know a 95 % coverage to +-1.3 % (binomial), so the
band 0.91-0.99 is three of those either side. Output error's lateral power of the correction
(``LATERAL_LEVERAGE_POWER``, (1 - H_f)^1.5 instead of HC3's square) gives ratio
0.93-1.07 here: 300 draws know a scatter to +-4 % (1/sqrt(600)), so 0.88-1.12 is three
of those either side.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from flightid.identification.engine.bounds import (
    LATERAL_LEVERAGE_POWER,
    colored_residual_covariance,
)

N, P, DRAWS = 600, 8, 300


def _coverage(leverage: bool, power: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    x = np.column_stack([lfilter([1], [1, -0.98], rng.normal(size=N)) for _ in range(P)])
    x /= x.std(axis=0)
    theta = rng.normal(size=P)
    hits, errors, stds = [], [], []
    for _ in range(DRAWS):
        v = 0.1 * lfilter([1], [1, -0.95], rng.normal(size=N))
        y = x @ theta + v
        est, *_ = np.linalg.lstsq(x, y, rcond=None)
        r = y - x @ est
        s2 = r @ r / N
        cov = colored_residual_covariance(x[:, None, :], r[:, None], np.array([[1 / s2]]),
                                          x.T @ x / s2, leverage=leverage, power=power)
        sd = np.sqrt(np.diag(cov))
        hits.append(np.abs(est - theta) <= 1.96 * sd)
        errors.append(est - theta)
        stds.append(sd)
    ratio = np.std(errors, axis=0) / np.mean(stds, axis=0)
    return np.mean(hits, axis=0), ratio


def test_leverage_corrected_bounds_cover_the_truth():
    coverage, ratio = _coverage(leverage=True)
    assert np.all((coverage >= 0.91) & (coverage <= 0.99)), coverage
    assert np.all((ratio > 0.7) & (ratio < 1.1)), ratio


def test_the_plain_sample_spectrum_is_optimistic_here():
    coverage, ratio = _coverage(leverage=False)
    assert np.mean(coverage) < 0.85 and np.max(ratio) > 1.4, (coverage, ratio)


def test_output_errors_power_sizes_the_bounds_to_the_scatter():
    _, ratio = _coverage(leverage=True, power=LATERAL_LEVERAGE_POWER)
    assert np.all((ratio > 0.88) & (ratio < 1.12)), ratio
