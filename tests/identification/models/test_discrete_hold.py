"""The discrete model's input holds against the continuous-time solution.

A lightly damped 2-state system (poles -1 +- 2.8j rad/s) driven by a 7 rad/s sine sampled
at 50 Hz, the Dutch-roll band of the Navion's records: the discrete states against
scipy's adaptive integration of the continuous model (relative tolerance 1e-11). The
error of a hold that interpolates the input follows its interpolation error: linear
('foh'), O(dt^2), (omega dt)^2 / 8 = 2.5e-3 of the input's amplitude at most between
samples; Catmull-Rom ('cubic'), O(dt^3), exact for quadratics.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.integrate

from flightid.identification.methods.filter_error.kalman_filter import process_noise_covariance
from flightid.identification.models.discrete import discretize, hold_inputs, propagate

A = np.array([[-1.3, 2.0], [-4.0, -0.7]])
B = np.array([[0.5], [1.2]])
DT = 0.02
OMEGA = 7.0


def _relative_error(hold: str) -> float:
    t = np.arange(0.0, 2.0, DT)
    u = np.sin(OMEGA * t)[:, None]
    phi, gamma, _, _ = discretize(A, B, DT, np.zeros((0, 2, 2)), np.zeros((0, 2, 1)), hold)
    x = propagate(phi, hold_inputs(u, hold) @ gamma.T, np.zeros(2))
    exact = scipy.integrate.solve_ivp(lambda s, y: A @ y + B[:, 0] * np.sin(OMEGA * s),
                                      (0.0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-11,
                                      atol=1e-13).y.T
    return float(np.max(np.abs(x - exact)) / np.max(np.abs(exact)))


def test_cubic_hold_follows_a_smooth_input_far_closer_than_the_linear_one():
    foh, cubic = _relative_error("foh"), _relative_error("cubic")
    # measured 1.6e-3 (the linear hold's interpolation error, 2.5e-3 at most, filtered by
    # the system) and 6.4e-5
    assert 6e-4 < foh < 2.5e-3
    assert cubic < 1.2e-4
    assert cubic < foh / 10


def test_cubic_hold_is_exact_for_a_quadratic_input():
    # Catmull-Rom's central-difference slopes are exact for a quadratic (not a cubic);
    # the first and last intervals are linear (extrapolated samples), so the discrete
    # model starts from the exact state at the second sample and stops two before the end
    t = np.arange(0.0, 1.0, DT)
    u = 0.2 + 0.5 * t - 0.8 * t**2
    phi, gamma, _, _ = discretize(A, B, DT, np.zeros((0, 2, 2)), np.zeros((0, 2, 1)), "cubic")
    exact = scipy.integrate.solve_ivp(lambda s, y: A @ y + B[:, 0] * (0.2 + 0.5 * s - 0.8 * s**2),
                                      (0.0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-12,
                                      atol=1e-14).y.T
    forcing = hold_inputs(u[:, None], "cubic") @ gamma.T
    x = propagate(phi, forcing[1:], exact[1])
    assert np.max(np.abs(x[:-2] - exact[1:-2])) < 1e-9 * np.max(np.abs(exact))


@pytest.mark.parametrize("hold", ["foh", "cubic"])
def test_input_matrix_derivatives_are_exact(hold):
    dA = np.zeros((1, 2, 2))
    dA[0, 0, 1] = 1.0
    dB = np.zeros((1, 2, 1))
    dB[0, 1, 0] = 1.0
    _, gamma, _, dgamma = discretize(A, B, DT, dA, dB, hold)
    h = 1e-6
    _, up, _, _ = discretize(A + h * dA[0], B + h * dB[0], DT, np.zeros((0, 2, 2)),
                             np.zeros((0, 2, 1)), hold)
    # forward difference of a smooth map: error ~ h |d2 Gamma| ~ 1e-8 of dGamma's scale
    assert np.max(np.abs((up - gamma) / h - dgamma[0])) < 1e-6 * np.max(np.abs(dgamma))


def test_an_exploding_trial_step_is_non_finite_without_a_warning() -> None:
    """An optimiser's trial step with a pole at +1e5 rad/s (e^2000 per step overflows a
    float) gives a non-finite transition matrix that the caller's cost rejects, and no
    RuntimeWarning reaches the user's terminal."""
    wild = np.array([[1e5, 0.0], [0.0, -0.7]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        phi, _, _, _ = discretize(wild, B, DT, np.zeros((0, 2, 2)), np.zeros((0, 2, 1)), "foh")
        q = process_noise_covariance(wild, np.eye(2), DT)
    assert not np.all(np.isfinite(phi))
    assert not np.all(np.isfinite(q))
