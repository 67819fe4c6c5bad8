"""The nuisance-bias budget of a fit that held a parameter: the held value is part of the
fitted model.

navion-doublets' elevator doublet (2 deg, 0.5 s pulses) moves the airspeed too little to
separate CL_0 from the alphadot and az biases, so output error holds CL_0 at its start
(the trim force balance) and the biases absorb its constant term, 2 CL_0 qbar S/(m V) in
alphadot with the measured, absolute V. The budget must rebuild the model with that held
value; without it the term was read as an excess (bias_alphadot 0.42 rad/s, bias_az
19.5 m/s^2) and the implausible-bias warning fired on a correct fit.
"""

from __future__ import annotations

import warnings

import pytest

from flightid.identification.data.reduction import standard_reduction
from flightid.identification.identify import identify
from flightid.identification.nuisance import ImplausibleBiasWarning, from_fit
from flightid.scenarios.cards import fly_card, load_card
from flightid.sim.jsbsim.model import quiet


@pytest.fixture(scope="module")
def longitudinal_fit():
    with quiet():
        measured, _ = fly_card(load_card("navion-doublets"), 1)
    record = standard_reduction(measured).record
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        est = identify(record, "oe", "lon")
    return est, caught


def test_a_held_cl0_is_no_implausible_bias(longitudinal_fit):
    est, caught = longitudinal_fit
    assert "CL_0" in est.unidentifiable  # the case this test is about
    assert "CL_0" in est.fit["fixed"]
    assert not [w for w in caught if issubclass(w.category, ImplausibleBiasWarning)]
    terms = {t.name: t for t in from_fit(est)}
    # the research suite's gyros and accelerometers have no bias, and the fit balances
    # the record's mean state: what is left is the noise of the mean rate and of the
    # kinematic specific force (measured 1.2e-5 rad/s and 0.03 m/s^2 on this flight),
    # far inside a gyro's 0.087 rad/s and an accelerometer's 1.96 m/s^2
    assert abs(terms["bias_alphadot"].excess) < 1e-3, terms["bias_alphadot"]
    assert abs(terms["bias_az"].excess) < 0.2, terms["bias_az"]
    # the held CL_0's term is in the trim part: qbar S/(m V) = 0.335 1/s here, so
    # 2 CL_0 qbar S/(m V) = 0.42 rad/s of the 0.49 rad/s fitted
    assert terms["bias_alphadot"].trim > 0.4
