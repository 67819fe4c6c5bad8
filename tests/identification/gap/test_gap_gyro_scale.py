"""A rate gyro's scale from the attitude kinematics (identification/gap/candidates/
gyro_scale.py): exact kinematics integrated by scipy (no air, no model), the null and the
missing channels, and on a real JSBSim flight of the blind check (seed 0's case 117, light
turbulence) where the diagnosis without the relation named ``control_effectiveness(da)``."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate

from flightid.identification.gap import diagnose
from flightid.identification.gap.candidates.gyro_scale import LEVEL, gyro_scale
from flightid.record import FlightRecord
from flightid.scenarios.gap_benchmark.cases import SINGLE, Case, Effect
from flightid.scenarios.gap_benchmark.classes import same
from flightid.scenarios.gap_benchmark.run import fly_case

RATE_HZ = 50.0


def _rates(t: np.ndarray) -> np.ndarray:
    """p, q, r (rad/s): sines of 0.15-0.5 Hz, a maneuver's band."""
    return np.array([0.30 * np.sin(2 * np.pi * 0.31 * t) + 0.1 * np.sin(2 * np.pi * 0.5 * t),
                     0.08 * np.sin(2 * np.pi * 0.23 * t + 0.4),
                     0.10 * np.sin(2 * np.pi * 0.15 * t + 1.0)])


def _windows(k_p: float = 1.0, k_q: float = 1.0) -> dict[str, FlightRecord]:
    """Three 10 s windows of phi, theta from the Euler kinematics of ``_rates`` (rtol
    1e-10), the gyros reading k_p p and k_q q."""
    t = np.arange(0.0, 30.0, 1.0 / RATE_HZ)

    def euler(s: float, y: np.ndarray) -> list[float]:
        p, q, r = _rates(np.array(s))
        phi, theta = y
        return [p + np.tan(theta) * (q * np.sin(phi) + r * np.cos(phi)),
                q * np.cos(phi) - r * np.sin(phi)]

    att = scipy.integrate.solve_ivp(euler, (0.0, t[-1]), [0.0, 0.05], t_eval=t,
                                    rtol=1e-10, atol=1e-12).y
    p, q, r = _rates(t)
    channels = {"phi": att[0], "theta": att[1], "p": k_p * p, "q": k_q * q, "r": r}
    return {f"w{j}": FlightRecord(t[sl] - t[sl][0], {c: v[sl] for c, v in channels.items()})
            for j, sl in enumerate(np.array_split(np.arange(t.size), 3))}


def test_exact_kinematics_give_the_gyro_scales():
    """A roll gyro reading 1.15 p and a pitch gyro 0.9 q are found at their factors. The
    differentiated attitude's truncation error, (omega dt)^2 / 6 = 7e-4 at 0.5 Hz and 50 Hz,
    bounds the error."""
    records = _windows(1.15, 0.9)
    roll, pitch = gyro_scale(records, "lateral"), gyro_scale(records, "longitudinal")
    assert roll.channel == "p" and roll.factor == pytest.approx(1.15, rel=1e-3)
    assert pitch.channel == "q" and pitch.factor == pytest.approx(0.9, rel=1e-3)
    assert roll.found and pitch.found
    assert roll.pooled > 0.9 and pitch.pooled > 0.9  # held out: most of the residual goes


def test_calibrated_gyros_are_not_found():
    """Both gyros at 1: the factors within the truncation error, nothing found."""
    records = _windows()
    for axis in ("lateral", "longitudinal"):
        found = gyro_scale(records, axis)
        assert found.factor == pytest.approx(1.0, abs=1e-3)
        assert not found.found


def test_without_attitudes_nothing_is_checked():
    """A hobby record (no phi, theta) gives None, not a guess."""
    records = {k: FlightRecord(r.time, {c: r[c] for c in ("p", "q", "r")})
               for k, r in _windows(1.2).items()}
    assert gyro_scale(records, "lateral") is None


def test_roll_gyro_scale_named_on_a_turbulent_flight():
    """Seed 0's case 117: a Telemaster roll gyro reading 1.125 p, light turbulence. Named
    ``scale(p)`` first, its factor within the relation's materiality level (``LEVEL``: 2 %
    of the factor; the null flights' factors are 1.0002-1.0024, docs/gap_benchmark.md)."""
    effect = Effect("scale", "lateral", "measured", {"channel": "p"},
                    {"factor": 1.1248641511223794})
    case = Case(117, 1400401494, "telemaster", SINGLE, (effect,))
    result = diagnose([fly_case(case, "light")], "telemaster", axis="lateral")
    assert result.named and same(effect, result.named[0]), [
        r.candidate.label for r in result.effects[:3]]
    assert result.named[0].values["scale_p"] == pytest.approx(1.1249, rel=LEVEL[1])
