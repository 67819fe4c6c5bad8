"""Filter error's measurement noise: estimated with the other parameters it is the
likelihood's minimum, where the relaxation's closed-form update was not.

The flight is realization 29 of the development study in docs/montecarlo.md ("Filter
error: the measurement noise estimated with the other parameters"): navion-demo, light
three-axis turbulence, research sensors, seed sub_seed(34001, "montecarlo:29"). There the
relaxation put the roll-rate gyro's noise at its lower bound (1.0e-4 rad/s against the
suite's 5.8e-4) with a Kalman gain K C = 1.00 on p, and the roll derivatives came out
4-8 Cramer-Rao bounds from the truth.
"""

from __future__ import annotations

import pytest

from flightid.identification.evaluation.scoring import record_truth
from flightid.identification.identify import identify
from flightid.scenarios.cards import fly_card, load_card

SEED = 2371788484  # sub_seed(34001, "montecarlo:29")
# the constant-condition lateral model these measurements were made with (the default
# before filter error took output error's known inputs, qbar(t) among them, and the
# first-order flight-condition correction instead)
# and the linear input hold they were made with (the cubic one, filter error's default
# since, moves this constant-condition fit's Cl_da from 2.55 to 3.06 bounds: the
# constant-condition model's own error, -1.3 % to -1.5 % of Cl_da, is not the hold's)
CONSTANT_CONDITION = {"dynamic_pressure": False, "propulsive_moments": False, "hold": "foh"}
# the derivatives the collapsed R_p biased together (too large in magnitude)
ROLL = ("Cl_beta", "Cl_da", "Cl_p")


@pytest.fixture(scope="module")
def fits():
    measured, flown = fly_card(load_card("navion-demo"), SEED)
    joint = identify(measured, "fem", "lateral", **CONSTANT_CONDITION)
    relaxed = identify(measured, "fem", "lateral", joint_noise=False, **CONSTANT_CONDITION)
    return record_truth(flown), joint, relaxed


def test_joint_noise_reaches_a_lower_likelihood_than_the_relaxation(fits):
    _, joint, relaxed = fits
    assert joint.fit["converged"], joint.fit["reason"]
    # the relaxation's stopping point: R_p at its floor, the filter following the gyro
    assert "p" in relaxed.fit["noise_at_lower_bound"]
    assert relaxed.fit["kalman_gain_times_C"][1] > 0.99
    # the same negative log-likelihood (J, 2250 samples) at both points: measured
    # -38720 against -37532. A difference of 1 in J is a likelihood ratio of e; 100 is
    # far beyond any sampling effect at one optimum
    assert joint.fit["cost"] < relaxed.fit["cost"] - 100.0
    # sigma_<output> are estimated parameters with their own bounds; the gyro's is no
    # longer at a floor (measured 2.2e-3 rad/s: the ML puts the part of the gust's roll
    # response that white process noise cannot represent there, 1.1-6.4 times the
    # sensor's 5.8e-4 on the 40 development flights)
    assert {"sigma_p", "sigma_beta"} <= set(joint.names)
    assert joint.fit["noise_at_lower_bound"].count("p") == 0
    # the joint fit's sigma_<output> has no bound: no output is reported at one, and one
    # below the relaxation's floor would be named apart; the relaxation has no such list
    assert joint.fit["noise_at_lower_bound"] == []
    assert "p" not in joint.fit["noise_below_floor"]
    assert relaxed.fit["noise_below_floor"] == []
    assert joint.fit["kalman_gain_times_C"][1] < 0.9
    # determined by the flight, not at a boundary (measured: robust bound 15 % of it)
    assert 0 < joint.std_of("sigma_p") < 0.5 * joint["sigma_p"]


def test_roll_derivatives_within_their_bounds_with_the_joint_noise(fits):
    truth, joint, relaxed = fits
    z_joint = {n: (joint[n] - truth[n]) / joint.std_of(n) for n in ROLL}
    z_relaxed = {n: (relaxed[n] - truth[n]) / relaxed.std_of(n) for n in ROLL}
    # each within 3 of its bounds (3 at once: a miss beyond 3 has 0.8 % probability with
    # right bounds); measured +0.2, +2.6, +1.2 with the information sandwich (+0.2, +1.6,
    # +0.7 with the larger of it and the Hessian one). (Cl_r, -4.2 on this flight, and
    # Cl_dr, +5.2, keep the misses of docs/montecarlo.md)
    assert max(abs(v) for v in z_joint.values()) < 3.0, z_joint
    # the relaxation's estimates of the same flight were outside: measured -4.4, -3.2, -4.2
    assert max(abs(v) for v in z_relaxed.values()) > 3.0, z_relaxed
