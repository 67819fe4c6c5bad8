"""Card overrides from the command line (``--set``, ``--turbulence``, ``--sensors``) for
``simulate``, ``montecarlo`` and ``design-compare``, and the ``ideal`` suite through
``identify``."""

from __future__ import annotations

import json
import tomllib

import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.record import read
from flightid.scenarios.cards import CardError, load_card, overridden_card, override
from flightid.units import DEG

runner = CliRunner()


def test_override_sets_any_field_by_its_toml_path():
    card = load_card("twinotter-lateral-0alpha")
    before = json.dumps(card.data, sort_keys=True)
    data = override(card.data, ["sensors.drop=vanes,lever_arm", "condition.speed=60",
                                "maneuver[1].amplitude_deg=-4.5", "seed=7"],
                    turbulence="light")
    assert json.dumps(card.data, sort_keys=True) == before  # the card itself is unchanged
    assert data["sensors"]["drop"] == ["vanes", "lever_arm"]
    assert data["condition"]["speed"] == 60 and data["seed"] == 7
    assert data["disturbance"] == [{"kind": "turbulence", "intensity": "light"}]
    flown = overridden_card(card, ["sensors.drop=vanes", "condition.speed=60",
                                   "maneuver[1].amplitude_deg=-4.5"], turbulence="moderate")
    assert flown.condition.speed_m_s == 60.0
    assert [m.name for m in flown.sensors.mounting] == ["lever_arm"]  # one name: a list
    assert flown.maneuvers[1].amplitude == pytest.approx(-4.5 * DEG)
    assert flown.disturbances[0].intensity == "moderate"
    hobby = overridden_card(card, sensors="hobby", turbulence="none")
    assert hobby.sensors.name == "hobby" and hobby.disturbances == ()


def test_override_refuses_an_unknown_path_naming_it_and_the_valid_keys():
    card = load_card("navion-demo")
    with pytest.raises(ValueError, match=r"condition\.sped.*valid keys: altitude, speed"):
        override(card.data, ["condition.sped=60"])
    with pytest.raises(ValueError, match=r"sensors\.mount.*valid keys: suite, output_rate"):
        override(card.data, ["sensors.mount=1"])
    with pytest.raises(ValueError, match=r"maneuver has 3 entries"):
        override(card.data, ["maneuver[3].start=1"])
    with pytest.raises(ValueError, match=r"disturbance\[0\]\.kind: the card has no disturbance"):
        override(load_card("twinotter-id").data, ["disturbance[0].kind=gust"])
    with pytest.raises(ValueError, match="--turbulence must be one of none, light, moderate"):
        override(card.data, turbulence="severe")
    # the card's own checks apply to the overridden card
    with pytest.raises(CardError, match=r"sensors\.drop\[0\].*'gps' is neither a channel"):
        overridden_card(card, ["sensors.drop=gps"])
    with pytest.raises(CardError, match=r"maneuver\[0\]\.foo.*allowed: amplitude"):
        overridden_card(card, ["maneuver[0].foo=1"])


def test_simulate_flies_the_overridden_card_and_refuses_a_bad_override(tmp_path):
    out = tmp_path / "f.parquet"
    result = runner.invoke(app, ["simulate", "telemaster-elevator-doublet", "-o", str(out),
                                 "--sensors", "research", "--set", "sensors.drop=vanes",
                                 "--set", "condition.speed=17", "--turbulence", "none"])
    assert result.exit_code == 0, result.output
    flown = read(out).meta.scenario["card"]
    assert flown["sensors"] == {"suite": "research", "drop": ["vanes"]}
    assert flown["condition"]["speed"] == 17 and "disturbance" not in flown
    assert read(out).meta.sample_rate == 50.0  # the research suite's rate, not hobby's 100
    bad = runner.invoke(app, ["simulate", "telemaster-elevator-doublet", "-o", str(out),
                              "--set", "condition.sped=17"])
    assert bad.exit_code == 2
    assert "condition.sped" in bad.output and "valid keys: altitude, speed" in bad.output


def test_studies_fly_the_overridden_card(tmp_path):
    study = tmp_path / "mc"
    result = runner.invoke(app, ["montecarlo", "telemaster-elevator-doublet", "-n", "1",
                                 "-o", str(study), "--method", "ee", "--model", "lon",
                                 "--workers", "1", "--quiet", "--format", "json",
                                 "--set", "condition.speed=17", "--sensors", "ideal"])
    assert result.exit_code == 0, result.output
    card = tomllib.loads((study / "card.toml").read_text())
    assert card["condition"]["speed"] == 17 and card["sensors"] == {"suite": "ideal"}
    assert card["name"] == "telemaster-elevator-doublet"
    assert json.loads(result.output[result.output.index("{"):])["realizations"] == 1
    compared = tmp_path / "dc"
    result = runner.invoke(app, ["design-compare", "--card", "telemaster-elevator-doublet",
                                 "-n", "1", "-o", str(compared), "--design", "doublet",
                                 "--method", "ee", "--workers", "1", "--quiet",
                                 "--format", "json", "--turbulence", "light"])
    assert result.exit_code == 0, result.output
    card = tomllib.loads((compared / "card.toml").read_text())
    assert card["disturbance"] == [{"kind": "turbulence", "intensity": "light"}]
    design = tomllib.loads((compared / "cards" / "doublet.toml").read_text())
    assert design["disturbance"] == card["disturbance"]


def test_ideal_suite_records_carry_what_identify_needs(tmp_path):
    out = tmp_path / "ideal.parquet"
    result = runner.invoke(app, ["simulate", "twinotter-lateral-0alpha", "-o", str(out),
                                 "--sensors", "ideal"])
    assert result.exit_code == 0, result.output
    record = read(out)
    assert {"qbar", "mass", "Ixx", "Izz", "Ixz"} <= set(record.channels)
    result = runner.invoke(app, ["identify", str(out), "--format", "json"])
    assert result.exit_code == 0, result.output
    rows = {r["name"]: r for r in json.loads(result.stdout)["score"]["rows"]}
    # exact sensors: what is left is the linear model's structure error against the
    # nonlinear flight, 1.5 % at most on the well-excited derivatives (measured: 0.1-1.5 %)
    for name in ("CY_beta", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr"):
        row = rows[name]
        assert row["status"] == "estimated", row
        assert abs(row["estimate"] - row["truth"]) < 0.03 * abs(row["truth"]), row
