"""Identification on a bridged record gives the derivatives of the direct record.

The bridge carries the measured flight as MAVLink 2 over a real pty at 921,600 baud
(every message at the card's 50 Hz fits the budget); the recorder converts the tlog
back to a record, taking mass properties and geometry from the aircraft definition. The
MAVLink fields are float32 (relative resolution 6e-8) and servo PWM (1 us = 0.06 deg),
far below the sensor noise, so both records must give the same estimates within one
standard error.
"""

import pytest

from flightid.scenarios.cards import fly_card, load_card
from flightid.scenarios.demo import identify_flight
from flightid.sim.bridge.air.serve import BridgeConfig
from flightid.sim.bridge.ground.tlog import convert_tlog
from flightid.sim.bridge.loopback import record_bridged


@pytest.mark.parametrize("seed", [1, 4])
def test_bridged_record_identifies_like_the_direct_one(tmp_path, seed):
    card = load_card("navion-demo")
    measured, _ = fly_card(card, seed)
    air, ground = record_bridged(measured, tmp_path / "f.tlog", BridgeConfig(baud=921600))
    sent = air.per_source()
    assert all(d["sent"] == d["packets"] for d in sent.values()), sent  # nothing lost
    assert air.servo_saturated == 0
    bridged = convert_tlog(tmp_path / "f.tlog", aircraft=card.aircraft)
    assert bridged.meta.reference == measured.meta.reference
    # MAVLink carries no maneuver list nor a priori table: the ground side takes them
    # from the card it flew
    bridged.meta.extra.update({k: measured.meta.extra[k] for k in ("maneuvers", "a_priori")})
    direct = identify_flight(measured)
    via_link = identify_flight(bridged)
    for d, b in zip(direct, via_link, strict=True):
        assert d.names == b.names
        for name in d.names:
            if name.startswith("C"):
                assert abs(b[name] - d[name]) < d.std_of(name), (name, d[name], b[name])
