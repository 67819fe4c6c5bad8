"""Total-variation denoising of multistep surface measurements
(identification/data/input_denoising.py).

Synthetic multisteps from ``scenarios.inputs`` at several sample rates, amplitudes and noise
levels (fixed seeds); the errors-in-variables effect on a JSBSim flight is in
test_card_recovery (Telemaster card lateral)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from flightid.identification.data import input_denoising as den
from flightid.scenarios.inputs import Multistep
from flightid.units import DEG

# (name, sample rate Hz, multistep, white-noise std rad): a 2-1-1, a doublet and a 3211
CASES = [
    ("211 at 25 Hz", 25.0, Multistep(surface="da", start=2.0, base=0.3, widths=(2, 1, 1),
                                     signs=(1, -1, 1), amplitude=2 * DEG), 0.2 * DEG),
    ("doublet at 50 Hz", 50.0, Multistep(surface="de", start=1.0, base=0.5, widths=(1, 1),
                                         signs=(1, -1), amplitude=4 * DEG), 0.5 * DEG),
    ("3211 at 100 Hz", 100.0, Multistep(surface="dr", start=3.0, base=0.4,
                                        widths=(3, 2, 1, 1), signs=(1, -1, 1, -1),
                                        amplitude=1.5 * DEG), 0.1 * DEG),
]


def _measured(rate: float, design: Multistep, sigma: float, seed: int):
    t = np.arange(0.0, design.end + 4.0, 1.0 / rate)
    true = design.signals(t)[design.surface]
    return true, true + np.random.default_rng(seed).normal(0.0, sigma, t.size)


@pytest.mark.parametrize("name,rate,design,sigma", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_noise_removed_and_plateaus_unbiased(name, rate, design, sigma, seed):
    true, y = _measured(rate, design, sigma, seed)
    x = den.piecewise_constant(y)
    # exactly the design's steps kept (no spurious ones), and the levels are means over
    # whole plateaus: the rms error is a small fraction of the raw noise (measured
    # 0.05-0.17 sigma on these cases; a quarter leaves room for other seeds)
    assert np.count_nonzero(np.diff(x)) == len(design.switch_times())
    assert np.sqrt(np.mean((x - true) ** 2)) < sigma / 4
    # each plateau is the mean of its samples: error within 4 standard errors of the mean
    t = np.arange(y.size) / rate
    switches = design.switch_times()
    for lo, hi in zip(switches[:-1], switches[1:], strict=True):
        inside = (t > lo + 1.5 / rate) & (t < hi - 1.5 / rate)
        level_error = np.mean(x[inside] - true[inside])
        assert abs(level_error) < 4 * sigma / np.sqrt(inside.sum() / 3), (lo, hi)


def test_noise_free_multistep_returned_exactly():
    design = CASES[0][2]
    t = np.arange(0.0, 8.0, 0.04)
    true = design.signals(t)["da"]
    assert np.allclose(den.piecewise_constant(true), true, atol=1e-12)


def test_total_variation_is_the_exact_minimiser():
    # against the dual solved by bounded-variable least squares (exact active set)
    true, y = _measured(25.0, CASES[0][2], 0.2 * DEG, seed=7)
    y = y[:80]
    lam = 0.6 * DEG
    n = y.size
    Dt = np.zeros((n, n - 1))
    Dt[np.arange(n - 1), np.arange(n - 1)] = -1.0
    Dt[np.arange(1, n), np.arange(n - 1)] = 1.0
    z = scipy.optimize.lsq_linear(Dt, y, bounds=(-lam, lam), method="bvls").x
    # to 1e-4 lambda (6e-5 deg here), far below the noise; L-BFGS-B stops near 1e-6 lambda
    assert np.allclose(den.total_variation(y, lam), y - Dt @ z, rtol=0, atol=1e-4 * lam)


def test_bad_signals_are_named():
    with pytest.raises(ValueError, match="NaN or inf"):
        den.piecewise_constant(np.array([0.0, np.nan, 1.0, 1.0]))
    with pytest.raises(ValueError, match="1-D"):
        den.total_variation(np.zeros((3, 3)), 0.1)
    with pytest.raises(ValueError, match="lambda must be finite"):
        den.total_variation(np.zeros(5), -1.0)
