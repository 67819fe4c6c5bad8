"""Confidence intervals of a study's statistics (scenarios/montecarlo/intervals.py): the
ratio of two scatters against the F distribution, one scatter against chi-square, a
coverage against the exact binomial interval; and that each covers the truth as often as
it says on fixed-seed normal samples."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.scenarios.montecarlo.intervals import (
    binomial_band,
    binomial_interval,
    interval_text,
    scatter_interval,
    scatter_ratio_interval,
)
from flightid.scenarios.montecarlo.report import render
from flightid.scenarios.montecarlo.summary import summarize


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


def test_binomial_band_is_the_binomial_quantiles_and_holds_the_nominal_share():
    """The 99 % band of a 95 % share at n = 200 is scipy's Binomial quantiles over n
    (0.905-0.985), and a coverage falls outside it about 1 % of the time when the bounds
    are right (4000 fixed-seed draws: 0.2-2 %, the binomial's discreteness keeps it under
    1 %)."""
    low, high = binomial_band(200, 0.95, 0.99)
    a, b = stats.binom.interval(0.99, 200, 0.95)
    assert (low, high) == (a / 200, b / 200)
    assert low < 0.95 < high
    draws = np.random.default_rng(3).binomial(200, 0.95, 4000) / 200
    outside = np.mean((draws < low) | (draws > high))
    assert 0.002 <= outside <= 0.02
    assert all(math.isnan(x) for x in binomial_band(0))


def _study_rows(n: int, bound_scale: float, name: str, rng: np.random.Generator) -> list:
    """n realizations of one derivative whose errors are N(0, 1) and whose reported
    standard error is ``bound_scale`` (1: right bounds)."""
    err = rng.standard_normal(n)
    return [{"index": i, "status": STATUS_ESTIMATED, "name": name, "estimate": 1.0 + e,
             "std": bound_scale, "error": e, "truth": 1.0, "reason": ""}
            for i, e in enumerate(err)]


def test_optimistic_bounds_are_warned_about_right_ones_are_not():
    """60 realizations: bounds of half the scatter cover about 68 %, outside the 99 % band
    (0.87-1.00 at n = 60): warned as optimistic, in the summary and the report; right
    bounds are not warned about."""
    rng = np.random.default_rng(7)
    df = pd.DataFrame(_study_rows(60, 1.0, "Cl_p", rng) + _study_rows(60, 0.5, "Cn_r", rng))
    summary = summarize(df)
    assert summary.row("Cl_p").coverage_warning == ""
    warned = summary.row("Cn_r")
    assert warned.coverage < 0.8 and "optimistic" in warned.coverage_warning
    assert summary.warnings() == [f"Cn_r: {warned.coverage_warning}"]
    assert "Warning</b>: Cn_r: coverage" in render(df, summary, "t", pngs={})
    assert summary.as_dict()["rows"][1]["coverage_warning"] == warned.coverage_warning


def test_interval_text_shows_on_which_side_of_parity_an_interval_lies():
    # a lower end of 1.0021 called "larger" must not read as "1 - 1.39"
    assert interval_text(1.0021, 1.39) == "1.002 - 1.39"
    assert interval_text(0.9996, 1.5) == "0.9996 - 1.50"
    assert interval_text(0.421, 0.558) == "0.421 - 0.558"
    assert interval_text(1.0, 2.0) == "1.00 - 2.00"
    assert interval_text(float("nan"), 1.2) == "-"
