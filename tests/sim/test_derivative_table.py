"""The condition-dependent catalogue entry ``derivative_table`` (issue 35 item 2): a delta
to one derivative as a JSBSim <table> in airspeed or alpha, written into an augmented
aircraft like the other airframe effects and injectable from a card's [[effect]]."""

from __future__ import annotations

import pytest

from flightid.scenarios.cards import augmented_aircraft, card_from_dict, load_card, trim_card
from flightid.sim.effects.airframe import DerivativeTable
from flightid.sim.effects.catalogue import CATALOGUE
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives

TABLE = DerivativeTable(derivative="Cn_beta", axes="body", delta_low=0.02, delta_high=-0.01,
                        low=50.0, high=72.0)


@pytest.mark.parametrize("speed", [45.0, 61.0, 80.0])
def test_truth_moves_by_the_table_value(speed):
    base = load("twinotter")
    aug = load(augmented_aircraft("twinotter", (TABLE,)))
    before = derivatives(base, trim(base, 1800.0, speed), axes="body").values
    after = derivatives(aug, trim(aug, 1800.0, speed), axes="body").values
    # the table is linear in airspeed and clamps at its ends; the truth's central
    # differences are exact to roundoff for a term linear in beta (measured 1e-15)
    assert after["Cn_beta"] - before["Cn_beta"] == pytest.approx(TABLE.at(speed), abs=1e-9)
    assert after["Cl_beta"] == pytest.approx(before["Cl_beta"], abs=1e-12)


def test_alpha_schedule_reads_the_trim_alpha():
    e = DerivativeTable(derivative="Cl_beta", axes="body", delta_low=-0.02, delta_high=0.02,
                        low=0.0, high=0.1, schedule="alpha")
    aug = load(augmented_aircraft("twinotter", (e,)))
    base = load("twinotter")
    t = trim(aug, 1800.0, 55.0)
    diff = (derivatives(aug, t, axes="body").values["Cl_beta"]
            - derivatives(base, trim(base, 1800.0, 55.0), axes="body").values["Cl_beta"])
    assert diff == pytest.approx(e.at(t.alpha), abs=1e-6)


def test_a_card_injects_it():
    data = dict(load_card("twinotter-id").data)
    data["effect"] = [{"name": "derivative_table", "derivative": "Cn_beta", "axes": "body",
                       "delta_low": 0.01, "delta_high": 0.0, "low": 50.0, "high": 70.0}]
    card = card_from_dict(data)
    assert card.augmentation == (DerivativeTable(derivative="Cn_beta", axes="body",
                                                 delta_low=0.01, delta_high=0.0, low=50.0,
                                                 high=70.0),)
    model, trimmed = trim_card(card)
    assert "augmented" in model.name and trimmed.speed_m_s == pytest.approx(61.733333)


def test_registered_once_in_the_catalogue():
    entry = CATALOGUE["derivative_table"]
    assert entry.implementation is DerivativeTable
    assert [p.name for p in entry.parameters] == ["delta_low", "delta_high", "low", "high"]


@pytest.mark.parametrize("kwargs, message", [
    ({"derivative": "Cm_alpha", "schedule": "alpha"}, "cannot be scheduled in alpha"),
    ({"low": 70.0, "high": 50.0}, "field 'high'"),
    ({"schedule": "mach"}, "field 'schedule'"),
])
def test_bad_tables_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        DerivativeTable(**kwargs)
