"""The gap diagnosis on the longitudinal axis: tail ice named against the clean Twin Otter,
and the axis chosen from what the records excite."""

from __future__ import annotations

import pytest

from flightid.identification.data.axes import excited_axes
from flightid.identification.gap import diagnose, write_aircraft
from flightid.identification.gap.jsbsim.refly import refly
from flightid.identification.gap.report import html_report
from flightid.record import read
from flightid.scenarios.cards import card_from_dict, fly_card, load_card
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives
from flightid.units import DEG
from tests.conftest import TWIN_OTTER

ALTITUDE, SPEED = 1890.0, 61.7  # TM-4099's 120 kt, the NASA record's altitude


def _elevator_card(aircraft: str, altitude: float = ALTITUDE, speed: float = SPEED) -> dict:
    """Two elevator maneuvers (3211, doublet; 2 deg) 16 s apart, no turbulence; research
    sensors after the compatibility check (vane position and upwash, IMU lever arm
    calibrated out, as the navion-demo card: a vane 4.5 m ahead reads alpha - 4.5 q/V,
    which the gap would name first)."""
    return {"name": "gap-elevator", "aircraft": aircraft, "duration": 32.0, "rate": 100.0,
            "seed": 1, "condition": {"altitude": altitude, "speed": speed},
            "maneuver": [{"kind": "3211", "surface": "de", "start": 2.0, "base": 0.5,
                          "amplitude_deg": 2.0},
                         {"kind": "doublet", "surface": "de", "start": 18.0, "base": 1.0,
                          "amplitude_deg": 2.0}],
            "sensors": {"suite": "research", "output_rate": 20.0,
                        "drop": ["vanes", "lever_arm"]}}


def _truth(aircraft: str) -> dict[str, float]:
    m = load(aircraft)
    return derivatives(m, trim(m, ALTITUDE, SPEED), axes="stability").values


@pytest.fixture(scope="module")
def iced_record():
    rec, _ = fly_card(card_from_dict(_elevator_card("twinotter-iced")))
    return rec


@pytest.fixture(scope="module")
def iced(iced_record):
    return diagnose([iced_record], "twinotter", try_pairs=False, steps=1, refine=True)


def test_tail_ice_named_as_tail_effectiveness_loss(iced):
    assert iced.axis == "longitudinal"
    top = iced.named[0]
    assert top.candidate.entry == "tail_ice"
    clean, ice = _truth("twinotter"), _truth("twinotter-iced")
    for part, d in (("elevator", "Cm_de"), ("stability", "Cm_alpha"), ("damping", "Cm_q")):
        real = ice[d] / clean[d] - 1.0  # the iced factor's change: -0.15, -0.10, -0.10
        est = top.parameters[part]["value"] - 1.0
        assert est * real > 0  # the right direction: less effectiveness, stability, damping
        # the ranking's linearised model leaves the changes 7-10 % short, with the sensors
        # and without them (docs/gap.md); 15 %: that measured misfit, not noise. The
        # refit with JSBSim (test_tail_ice_refined_within_3_standard_errors) closes it.
        assert abs(est - real) < 0.15 * abs(real), d
    s = iced.shrinkage()
    assert s["overall"]["shrink"] > 0.7
    for ch in ("alpha", "q", "az"):
        assert s["channels"][ch]["shrink"] > 0.7
    d = iced.to_json()
    assert d["axis"] == "longitudinal" and d["named"][0]["name"] == "tail_ice"
    assert set(d["named"][0]["parameters"]) == {"elevator", "stability", "damping"}


def test_tail_ice_refined_within_3_standard_errors(iced):
    """The issue's criterion: tail ice named, each estimated change within 3 standard
    errors of the real one. The refit flies the augmented Twin Otter with the record's
    measured elevator driven past its actuator (``gap.refine``). Measured on this card
    (seed 1): 0.8510 +- 0.0012, 0.9008 +- 0.0025, 0.9049 +- 0.0035 (0.8, 0.3, 1.4 standard
    errors); seeds 2-5 within 3 too, the worst -2.8 (docs/gap.md)."""
    refined = iced.refined
    assert refined is not None and refined.effect.name == "tail_ice"
    clean, ice = _truth("twinotter"), _truth("twinotter-iced")
    for part, d in (("elevator", "Cm_de"), ("stability", "Cm_alpha"), ("damping", "Cm_q")):
        real = ice[d] / clean[d]
        p = refined.parameters[part]
        assert abs(p["value"] - real) < 3 * p["std"], (part, p, real)
        # no farther than the ranking's linear value, to within one standard error (the
        # linear damping factor came out 0.2 % off once the Twin Otter's engines hold
        # their trimmed power: refined 0.00198, linear 0.00192 from the real one)
        assert abs(p["value"] - real) < abs(refined.linear[part]["value"] - real) + p["std"], \
            part
    assert abs(refined.offsets["de"]) < 0.01 * DEG  # the trim surface: noise, quantization
    d = iced.to_json()["refined"]
    assert d["name"] == "tail_ice" and set(d["parameters"]) == {"elevator", "stability",
                                                                  "damping"}
    assert "Refined with JSBSim" in html_report(iced)


def test_tail_ice_corrected_aircraft(iced, iced_record, tmp_path):
    """The named tail ice written into the Twin Otter (``write_aircraft``): its truth's
    pitching-moment derivatives are the clean ones times the refined factors, its lift
    derivatives unchanged; flown again with the record's elevator (``refly``, the
    longitudinal channels) it closes the gap of the clean Twin Otter: 0.0080 -> 0.00032
    measured (96 %; 0.00038 with the ranking's values); what is left is sensor noise."""
    path = write_aircraft(iced, tmp_path)
    again = refly(iced, [iced_record], tmp_path, path)
    assert all(set(w["channels"]) == {"V", "alpha", "q", "theta", "az"}
               for w in again["windows"])
    assert again["overall"]["shrink"] > 0.9, again["overall"]
    clean, corrected = _truth("twinotter"), _truth(str(path))
    p = iced.refined.parameters
    for part, d in (("elevator", "Cm_de"), ("stability", "Cm_alpha"), ("damping", "Cm_q")):
        assert corrected[d] == pytest.approx(p[part]["value"] * clean[d], rel=1e-3)
    assert corrected["CL_de"] == pytest.approx(clean["CL_de"], rel=1e-3)


def test_navion_blind_cm_alpha():
    """A Cm_alpha delta of +0.1 (stability axes; the Navion's -0.683 -> -0.583) flown at
    Teper's condition (sea level, 53.645 m/s) and diagnosed without being told."""
    data = _elevator_card("navion", 0.0, 53.645)
    data["effect"] = [{"name": "derivative_delta", "derivative": "Cm_alpha", "delta": 0.1}]
    rec, _ = fly_card(card_from_dict(data))
    result = diagnose([rec], "navion", try_pairs=False, steps=1, refine=True)
    top = result.named[0]
    assert (top.candidate.entry, top.candidate.options["derivative"]) == \
        ("derivative_delta", "Cm_alpha")
    delta = top.parameters["delta"]
    # measured +0.0936 +- 0.0030 (docs/gap.md); 3 bounds or 10 % as the lateral blind case
    assert abs(delta["value"] - 0.1) < max(3 * delta["std"], 0.01)
    assert result.shrinkage()["overall"]["shrink"] > 0.7
    # the JSBSim refit: +0.09946 +- 0.00054 measured (1.0 bound), a seventh of the linear one
    refined = result.refined.parameters["delta"]
    assert abs(refined["value"] - 0.1) < 3 * refined["std"], refined
    assert refined["std"] < 0.3 * delta["std"]


def test_axes_excited():
    demo, _ = fly_card(load_card("navion-demo"))  # elevator 3211, aileron, rudder
    assert excited_axes([demo]) == ["lateral", "longitudinal"]
    elevator, _ = fly_card(card_from_dict(_elevator_card("twinotter")))
    assert excited_axes([elevator]) == ["longitudinal"]
    if TWIN_OTTER.is_file():  # rudder and aileron; elevator spread 7 % of the aileron's
        assert excited_axes([read(TWIN_OTTER)]) == ["lateral"]


def test_axis_argument_checked():
    elevator, _ = fly_card(card_from_dict(_elevator_card("twinotter")))
    with pytest.raises(ValueError, match="axis must be"):
        diagnose([elevator], "twinotter", axis="pitch")
    with pytest.raises(ValueError, match="no lateral maneuver"):
        diagnose([elevator], "twinotter", axis="lateral")
