"""A flight without surface inputs, or a record of pure noise, is refused by every method
with the reason: no confident numbers from data that cannot support them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flightid.identification.identify import identify
from flightid.identification.methods import registry
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card

NOISY = ("de", "da", "dr", "alpha", "beta", "p", "q", "r", "phi", "theta")
# the accelerometers keep gravity (their trim specific force) under the noise: the unit
# check refuses a record that does not feel it
FORCES = ("ax", "ay", "az")


@pytest.fixture(scope="module")
def quiet_flight() -> FlightRecord:
    """The Navion demo card flown without its maneuvers: light turbulence, research sensors."""
    card = dataclasses.replace(load_card("navion-demo"), maneuvers=())
    measured, _ = fly_card(card, 2)
    return measured


@pytest.fixture(scope="module")
def pure_noise(quiet_flight) -> FlightRecord:
    rng = np.random.default_rng(7)
    channels = {k: rng.normal(0.0, 0.01, len(quiet_flight)) if k in NOISY else v
                for k, v in quiet_flight.channels.items()}
    channels.update({k: np.median(quiet_flight[k]) + rng.normal(0.0, 0.01, len(quiet_flight))
                     for k in FORCES})
    return FlightRecord(quiet_flight.time, channels, quiet_flight.meta)


@pytest.mark.parametrize("method_id", sorted(registry.methods()))
@pytest.mark.parametrize("case", ["quiet_flight", "pure_noise"])
def test_every_method_refuses_with_the_reason(request, case, method_id):
    record = request.getfixturevalue(case)
    with pytest.raises(ValueError, match=r"no input is excited .*(noise only|constant)"):
        identify(record, method_id)


def test_an_excited_input_is_not_refused(quiet_flight):
    # the same quiet flight with a real aileron doublet in the record: accepted
    da = quiet_flight["da"].copy()
    t = quiet_flight.time
    da[(t > 10) & (t < 11)] += 0.05
    da[(t >= 11) & (t < 12)] -= 0.05
    record = quiet_flight.with_channels(da=da)
    est = identify(record, "ee", "Cl=beta+phat+rhat+da")
    assert "Cl_da" in est.names
