"""The model curve relocated to flight points (identification.envelope_fit): the form
chosen and its parameters recovered on points drawn about a known curve (fixed seed)."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.envelope_fit import fit_correction

X = np.linspace(50.0, 75.0, 6)
MODEL = np.full(X.size, 0.0864)
STD = np.full(X.size, 2e-4)


def _points(truth: np.ndarray, seed: int = 7) -> np.ndarray:
    return truth + np.random.default_rng(seed).normal(0.0, STD)


def test_agreement_keeps_the_model():
    c = fit_correction("Cn_beta", X, _points(MODEL), STD, MODEL)
    assert c.form == "none" and "agree" in c.reason


def test_a_level_error_is_a_shift():
    c = fit_correction("Cn_beta", X, _points(MODEL + 0.01), STD, MODEL)
    assert c.form in ("shift", "scale")
    # the weighted mean of 6 points: standard error 2e-4 / sqrt(6) = 8.2e-5; 4 of them
    assert float(c.delta(62.5, 0.0864)) == pytest.approx(0.01, abs=3.3e-4)


def test_a_trend_is_a_shift_and_slope():
    truth = MODEL + 0.015 - 0.03 * (X - 50.0) / 25.0
    c = fit_correction("Cn_beta", X, _points(truth), STD, MODEL)
    assert c.form == "shift+slope"
    # slope standard error: 2e-4 / sqrt(sum (x - mean)^2) = 2.6e-5 per m/s; 4 of them
    assert c.slope == pytest.approx(-0.0012, abs=1.1e-4)
    assert float(c.delta(50.0, 0.0864)) == pytest.approx(0.015, abs=6e-4)


def test_a_trend_without_a_table_is_not_forced():
    truth = MODEL + 0.015 - 0.03 * (X - 50.0) / 25.0
    c = fit_correction("Cn_beta", X, _points(truth), STD, MODEL, trend=False)
    assert c.form == "none" and "no form fits" in c.reason


def test_a_scale_error_is_a_scale():
    model = np.linspace(-5.5, -5.9, X.size)
    c = fit_correction("CZ_alpha", X, _points(1.1 * model), np.full(X.size, 5e-3), model,
                       trend=False)
    assert c.form == "scale" and c.scale == pytest.approx(1.1, abs=4e-3)
