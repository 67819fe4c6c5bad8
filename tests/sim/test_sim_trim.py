"""Trim with JSBSim's trim routine: straight, climbing, turning; specific errors for bad input."""

from __future__ import annotations

import math

import pytest

from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import TrimError, trim
from flightid.units import FT


@pytest.fixture(scope="module")
def c172p():
    return load("c172p")


def test_level_trim_balances_forces_and_moments(c172p):
    t = trim(c172p, 1000.0, 50.0)
    # JSBSim's trim tolerances are 1e-3 ft/s^2 and 1e-4 rad/s^2
    assert max(abs(t.residuals[k]) for k in ("udot", "vdot", "wdot")) < 1e-3 * FT
    assert max(abs(t.residuals[k]) for k in ("pdot", "qdot", "rdot")) < 1e-4
    assert t.theta == pytest.approx(t.alpha, abs=1e-6)  # level: gamma = theta - alpha = 0
    assert 0.0 < t.throttle < 1.0
    assert math.radians(-2) < t.alpha < math.radians(8)


def test_faster_flight_needs_less_alpha_and_more_throttle(c172p):
    slow, fast = trim(c172p, 1000.0, 45.0), trim(c172p, 1000.0, 60.0)
    assert fast.alpha < slow.alpha and fast.throttle > slow.throttle


def test_climb_sets_flight_path_angle(c172p):
    gamma = math.radians(3.0)
    t = trim(c172p, 1000.0, 45.0, gamma_rad=gamma)
    assert t.theta - t.alpha == pytest.approx(gamma, abs=1e-4)
    assert t.throttle > trim(c172p, 1000.0, 45.0).throttle


def test_coordinated_turn(c172p):
    bank = math.radians(30.0)
    t = trim(c172p, 1000.0, 50.0, bank_rad=bank)
    assert t.phi == pytest.approx(bank, abs=1e-6)
    # turn rate psidot = g tan(phi) / V; body yaw rate r = psidot cos(phi) cos(theta)
    g = c172p.get("accelerations/gravity-ft_sec2") * FT
    psidot = g * math.tan(bank) / 50.0
    r = t.jsbsim["ic/r-rad_sec"]
    assert r == pytest.approx(psidot * math.cos(bank) * math.cos(t.theta), rel=0.01)


@pytest.mark.parametrize(
    ("altitude", "speed", "match"),
    [
        (1000.0, -3.0, "speed must be positive"),
        (1000.0, 0.0, "speed must be positive"),
        (-5.0, 50.0, "altitude must be >= 0"),
        (30_000.0, 50.0, "absurd"),
        (1000.0, 400.0, "Mach 1.19 is absurd for a propeller aircraft"),
        (1000.0, 20.0, r"below stall \(CL needed 2\.\d+ > CLmax ~1\.\d+"),
        (1000.0, 85.0, r"throttle saturates at 1\.0 \(not enough power"),
    ],
)
def test_bad_conditions_raise_trim_error_naming_the_cause(c172p, altitude, speed, match):
    with pytest.raises(TrimError, match=match):
        trim(c172p, altitude, speed)


def test_trim_error_is_a_value_error():
    assert issubclass(TrimError, ValueError)


def test_unknown_aircraft_by_name():
    with pytest.raises(ValueError, match="unknown aircraft 'zeppelin9'"):
        trim("zeppelin9", 1000.0, 50.0)


def test_trim_on_dhc6_at_the_twin_otter_condition():
    t = trim("DHC6", 1920.0, 72.3)
    assert abs(t.alpha) < math.radians(3) and 0.3 < t.throttle < 1.0
