"""Confidence intervals of a study's statistics (scenarios/montecarlo/intervals.py): the
ratio of two scatters against the F distribution, one scatter against chi-square, a
coverage against the exact binomial interval; and that each covers the truth as often as
it says on fixed-seed normal samples."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from flightid.scenarios.montecarlo.intervals import (
    binomial_interval,
    scatter_interval,
    scatter_ratio_interval,
)


def test_scatter_ratio_interval_is_the_f_interval():
    # a ratio of 0.5 at n = 20 each: 0.5 / sqrt(F_0.95(19, 19)) .. 0.5 / sqrt(F_0.05(19, 19))
    low, high = scatter_ratio_interval(0.5, 20, 20, 0.90)
    assert low == pytest.approx(0.5 / math.sqrt(stats.f.ppf(0.95, 19, 19)), rel=1e-12)
    assert high == pytest.approx(0.5 / math.sqrt(stats.f.ppf(0.05, 19, 19)), rel=1e-12)
    assert (low, high) == pytest.approx((0.3396, 0.7362), abs=1e-4)
    # unequal n: the degrees of freedom in order (numerator a, denominator b)
    low, high = scatter_ratio_interval(1.2, 6, 30, 0.90)
    assert low == pytest.approx(1.2 / math.sqrt(stats.f.ppf(0.95, 5, 29)), rel=1e-12)
    assert high == pytest.approx(1.2 / math.sqrt(stats.f.ppf(0.05, 5, 29)), rel=1e-12)
    # at n = 6 a ratio of 0.5 is not told from 1; at n = 50 it is
    assert scatter_ratio_interval(0.5, 6, 6)[1] > 1 > scatter_ratio_interval(0.5, 50, 50)[1]
    assert all(math.isnan(v) for v in scatter_ratio_interval(0.5, 1, 20))
    with pytest.raises(ValueError, match="confidence level"):
        scatter_ratio_interval(0.5, 20, 20, 1.0)


def test_scatter_interval_is_the_chi_square_interval_about_16_percent_at_n_20():
    low, high = scatter_interval(1.0, 20, 0.90)
    assert low == pytest.approx(math.sqrt(19 / stats.chi2.ppf(0.95, 19)), rel=1e-12)
    assert high == pytest.approx(math.sqrt(19 / stats.chi2.ppf(0.05, 19)), rel=1e-12)
    # the "known only to about +-16 % at n = 20" is one standard error,
    # 1 / sqrt(2 (n - 1)) = 0.162: the 68 % interval is -13 % .. +21 %, the 90 % one
    # -21 % .. +37 %
    assert (low, high) == pytest.approx((0.7939, 1.3704), abs=1e-4)
    assert scatter_interval(1.0, 20, 0.6827) == pytest.approx((0.8708, 1.2115), abs=1e-4)


def test_binomial_interval_is_clopper_pearson():
    for k, n in ((19, 20), (0, 10), (10, 10), (57, 60), (3, 7)):
        ci = stats.binomtest(k, n).proportion_ci(0.95, method="exact")
        assert binomial_interval(k, n, 0.95) == pytest.approx((ci.low, ci.high), abs=1e-12)
    # known values: 19 of 20 covered gives 75.1-99.9 %; none of 10 gives 0-30.8 %
    assert binomial_interval(19, 20) == pytest.approx((0.7513, 0.9987), abs=1e-4)
    assert binomial_interval(0, 10) == pytest.approx((0.0, 0.3085), abs=1e-4)
    assert all(math.isnan(v) for v in binomial_interval(0, 0))
    with pytest.raises(ValueError, match="successes"):
        binomial_interval(11, 10)


def test_intervals_cover_the_truth_as_often_as_they_say():
    # 4000 fixed-seed pairs of normal samples (n = 6 and 9) with sigma_a / sigma_b = 0.7:
    # a 90 % interval must contain 0.7 in 90 % of them, within 3 binomial standard
    # deviations sqrt(0.9 0.1 / 4000) = 0.0047
    rng = np.random.default_rng(37)
    trials, na, nb, truth = 4000, 6, 9, 0.7
    a = rng.normal(0, truth, (trials, na)).std(axis=1, ddof=1)
    b = rng.normal(0, 1.0, (trials, nb)).std(axis=1, ddof=1)
    hits = [lo <= truth <= hi for lo, hi in
            (scatter_ratio_interval(r, na, nb, 0.9) for r in a / b)]
    assert np.mean(hits) == pytest.approx(0.9, abs=3 * 0.0047)
    one = [lo <= truth <= hi for lo, hi in (scatter_interval(s, na, 0.9) for s in a)]
    assert np.mean(one) == pytest.approx(0.9, abs=3 * 0.0047)
    # Clopper-Pearson is conservative: at least 95 % for a true share of 0.9 and n = 30
    k = rng.binomial(30, 0.9, trials)
    covered = [lo <= 0.9 <= hi for lo, hi in (binomial_interval(int(x), 30) for x in k)]
    assert np.mean(covered) >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / trials)
