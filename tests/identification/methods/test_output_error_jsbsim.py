"""Output error on JSBSim truth flights: the Navion lateral 3211 and 2-1-1; the Navion's
and the Telemaster's elevator doublet with the full longitudinal model."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.methods import output_error as oe
from flightid.identification.models import linear as lm
from flightid.identification.models.reference_condition import condition_from_record
from flightid.scenarios.inputs import Multistep, total_signals
from flightid.sim.flight import simulation as flight
from flightid.sim.jsbsim import trim as trimming
from flightid.sim.jsbsim import truth
from flightid.units import DEG

# aileron 3211 (1.5-1-0.5-0.5 s) and rudder 2-1-1 (1-0.5-0.5 s), 0.035 rad
AILERON = Multistep(surface="da", start=1.0, widths=(1.5, 1.0, 0.5, 0.5), signs=(1, -1, 1, -1),
                    amplitude=0.035)
RUDDER = Multistep(surface="dr", start=8.0, widths=(1.0, 0.5, 0.5), signs=(1, -1, 1),
                   amplitude=0.035)


@pytest.fixture(scope="module")
def navion_flight():
    trim = trimming.trim("navion", 1500.0, 55.0)
    rate, duration = 50.0, 20.0
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    controls = total_signals([AILERON, RUDDER], t)
    record = flight.fly("navion", trim, controls, duration_s=duration, rate_hz=rate)
    return record, truth.derivatives("navion", trim, axes="body")


def test_lateral_derivatives_of_a_jsbsim_flight(navion_flight):
    record, true = navion_flight
    est = oe.estimate(record, lm.lateral(condition_from_record(record)))
    assert est.fit["converged"], est.fit["reason"]
    assert est.unidentifiable == {}
    # Noise-free flight: what is left is model error. The linear model holds V, alpha and
    # theta at their means while the 2 deg maneuver moves them, and JSBSim's body-axis
    # derivatives are slopes at trim; that costs about 1-2 % on the large derivatives
    # (measured: at most 1.8 %, Cl_dr) and 3 % on Cn_p.
    for name in ("CY_beta", "CY_dr", "Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr",
                 "Cn_beta", "Cn_r", "Cn_dr"):
        assert est[name] == pytest.approx(true[name], rel=0.03), name
    assert est["Cn_p"] == pytest.approx(true["Cn_p"], rel=0.06)
    # CY_r is zero in the Navion's aerodynamics: the side force the estimate puts on the yaw
    # rate stays within the model error, 2 % of the side force from sideslip (measured 0.23 %)
    rhat = record["r"] * record.meta.reference.span / (2.0 * record["V"])
    from_yaw_rate = abs(est["CY_r"]) * np.max(np.abs(rhat))
    assert from_yaw_rate < 0.02 * abs(true["CY_beta"]) * np.max(np.abs(record["beta"]))


def test_rudder_terms_unidentifiable_on_an_aileron_only_jsbsim_flight():
    trim = trimming.trim("navion", 1500.0, 55.0)
    t = np.arange(0.0, 10.0 + 0.01, 0.02)
    record = flight.fly("navion", trim,
                        total_signals([AILERON], t),
                        duration_s=10.0, rate_hz=50.0)
    est = oe.estimate(record, lm.lateral(condition_from_record(record)))
    assert set(est.unidentifiable) == {"CY_dr", "Cl_dr", "Cn_dr"}
    assert all("input dr is not excited" in why for why in est.unidentifiable.values())
    true = truth.derivatives("navion", trim, axes="body")
    assert est["Cl_da"] == pytest.approx(true["Cl_da"], rel=0.03)


# (altitude m, speed m/s, flaps rad, doublet pulse width s): the Telemaster slow and at high
# lift (CL_0 0.93, thrust/(qbar S) 0.13), the Navion at cruise
LONGITUDINAL_CASES = {"telemaster": (30.0, 15.0, 5 * DEG, 0.45),
                      "navion": (1500.0, 55.0, 0.0, 0.6)}


@pytest.mark.parametrize("aircraft", list(LONGITUDINAL_CASES))
def test_longitudinal_model_with_thrust_and_body_az(aircraft):
    altitude, speed, flaps, width = LONGITUDINAL_CASES[aircraft]
    trim = trimming.trim(aircraft, altitude, speed, flaps_rad=flaps)
    rate, duration = 100.0, 10.0
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    doublet = Multistep(surface="de", start=1.0, widths=(width, width), signs=(1, -1),
                        amplitude=2 * DEG)
    record = flight.fly(aircraft, trim, total_signals([doublet], t), duration_s=duration,
                        rate_hz=rate)
    true = truth.derivatives(aircraft, trim, axes="stability")
    condition = condition_from_record(record)
    assert condition.thrust == pytest.approx(np.mean(record["thrust"]))
    # CL_q, Cm_alphadot a priori (as in the demo); CL_0 at the weight balance (with the
    # biases it is not separable); CD_de not excited apart from the other drag terms
    fixed = {n: true[n] for n in ("CL_q", "Cm_alphadot", "CD_de")}
    model = lm.longitudinal(condition, derivatives=lm.LONGITUDINAL_DERIVATIVES, start=fixed)
    free = [p for p in model.parameters if p not in (*fixed, "CL_0")]
    est = oe.estimate(record, model, free=free)
    assert est.fit["converged"], est.fit["reason"]
    # The trim thrust turning with alpha and the body-axis z force of the accelerometer
    # (linear_models.longitudinal): without them CL_alpha came out +2.94 % (Telemaster) and
    # +1.16 % (Navion); with them +0.04 % and -0.02 %. The rest is linear-model error of
    # the 2 deg doublet (measured at most 1.27 %, Telemaster Cm_alpha).
    assert est["CL_alpha"] == pytest.approx(true["CL_alpha"], rel=0.005)
    for name in ("CL_de", "Cm_alpha", "Cm_q", "Cm_de"):
        assert est[name] == pytest.approx(true[name], rel=0.015), name
