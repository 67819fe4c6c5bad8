"""Transfer-function fits with the CIFER cost: a known second order with delay."""

import numpy as np
import pytest
from scipy import signal

from flightid.identification.frequency.response import (
    FrequencyResponse,
    frequency_response_arrays,
)
from flightid.identification.frequency.transfer_function import (
    cifer_cost,
    coherence_weight,
    fit_transfer_function,
)

DT = 0.02


def sweep_data(wn, zeta, tau, duration=90.0):
    t = np.arange(0, duration, DT)
    u = signal.chirp(t, 0.05, t[-1], 4.0, method="logarithmic") * np.minimum(1.0, t / 3.0)
    sys = signal.lti([wn**2], [1, 2 * zeta * wn, wn**2])
    _, y, _ = signal.lsim(sys, np.interp(t - tau, t, u, left=0.0), t)
    return t, u, y


def test_cifer_weights_and_cost():
    assert coherence_weight(np.array([1.0]))[0] == pytest.approx((1.58 * (1 - np.exp(-1))) ** 2)
    assert coherence_weight(np.array([0.0]))[0] == 0.0
    # 1 dB magnitude error everywhere with coherence 1 -> J = 20 * W_gamma(1) * 1^2
    h = np.ones(10, dtype=complex)
    j = cifer_cost(h * 10 ** (1 / 20), h, np.ones(10))
    assert j == pytest.approx(20 * coherence_weight(np.array([1.0]))[0])
    # 10 deg phase error -> J = 20 W_gamma 0.01745 * 100
    j = cifer_cost(h * np.exp(1j * np.radians(10)), h, np.ones(10))
    assert j == pytest.approx(20 * coherence_weight(np.array([1.0]))[0] * 0.01745 * 100)


@pytest.mark.parametrize("wn,zeta,tau,seed", [(6.0, 0.4, 0.10, 0), (3.0, 0.2, 0.06, 1),
                                              (9.0, 0.6, 0.14, 2)])
def test_second_order_with_delay_is_recovered(wn, zeta, tau, seed):
    # Tolerances: the delay within one sample; natural frequency and damping within
    # 4 x (Cramer-Rao bound x 3.5), the ratio of Monte Carlo scatter to the CIFER bound
    # measured in test_cramer_rao_bounds_match_monte_carlo_scatter (Maine & Iliff 1985
    # report factors 2-5 for real data), plus the 1 % leakage bias of a windowed sweep.
    rng = np.random.default_rng(seed)
    t, u, y = sweep_data(wn, zeta, tau)
    y = y + 0.1 * np.std(y) * rng.standard_normal(t.size)
    fr = frequency_response_arrays({"u": u}, y, DT, frequencies=np.geomspace(0.1, 3.0, 60))["u"]
    fit = fit_transfer_function(fr, 0, 2)
    mode = fit.modes()[0]
    assert abs(fit.delay - tau) < DT
    assert abs(mode["natural_frequency"] - wn) < 14 * mode["natural_frequency_std"] + 0.01 * wn
    assert abs(mode["damping"] - zeta) < 14 * mode["damping_std"] + 0.01
    assert fit.cost < 50  # a correct structure fits well below the J <= 100 guideline
    assert np.all(fit.cr_percent < 20) and np.all(fit.insensitivity_percent < 10)
    # steady-state gain b0/a0 = 1
    assert fit.values[0] / fit.values[1] == pytest.approx(1.0, abs=0.03)


def test_cramer_rao_bounds_match_monte_carlo_scatter():
    # 20 noise realisations: the estimates scatter about the truth with a standard
    # deviation 1-5 times the CIFER Cramer-Rao bound (the bound ignores the correlation
    # of neighbouring frequency points and the leakage of windowing), and the mean is
    # within 3 scatter/sqrt(20) + 2 % of the truth.
    wn, zeta, tau = 6.0, 0.4, 0.1
    t, u, y0 = sweep_data(wn, zeta, tau)
    est = []
    for seed in range(20):
        rng = np.random.default_rng(100 + seed)
        y = y0 + 0.3 * np.std(y0) * rng.standard_normal(t.size)
        fr = frequency_response_arrays({"u": u}, y, DT,
                                       frequencies=np.geomspace(0.1, 3.0, 60))["u"]
        fit = fit_transfer_function(fr, 0, 2)
        m = fit.modes()[0]
        est.append([m["natural_frequency"], m["damping"], fit.delay,
                    m["natural_frequency_std"], m["damping_std"], fit.std_of("tau")])
    est = np.array(est)
    scatter = est[:, :3].std(axis=0, ddof=1)
    bound = est[:, 3:].mean(axis=0)
    ratio = scatter / bound
    assert np.all((ratio > 1.0) & (ratio < 5.0)), ratio
    truth = np.array([wn, zeta, tau])
    assert np.all(np.abs(est[:, :3].mean(axis=0) - truth)
                  < 3 * scatter / np.sqrt(20) + 0.02 * truth)


def test_wrong_order_costs_more_and_fixed_delay():
    rng = np.random.default_rng(4)
    t, u, y = sweep_data(6.0, 0.4, 0.1)
    y = y + 0.1 * np.std(y) * rng.standard_normal(t.size)
    fr = frequency_response_arrays({"u": u}, y, DT, frequencies=np.geomspace(0.1, 3.0, 60))["u"]
    good = fit_transfer_function(fr, 0, 2)
    first = fit_transfer_function(fr, 0, 1)
    assert first.cost > 5 * good.cost
    fixed = fit_transfer_function(fr, 0, 2, delay=0.1)
    assert "tau" not in fixed.names and fixed.delay == 0.1
    assert fixed.modes()[0]["natural_frequency"] == pytest.approx(6.0, rel=0.03)


def test_too_few_coherent_points_is_a_clear_error():
    f = np.geomspace(0.1, 1.0, 10)
    fr = FrequencyResponse(f, np.ones(10), np.full(10, 0.3), np.full(10, 0.5),
                           input="de", output="q")
    with pytest.raises(ValueError, match="coherence >= 0.6"):
        fit_transfer_function(fr, 0, 2)
    with pytest.raises(ValueError, match="order"):
        fit_transfer_function(fr, 3, 2)
