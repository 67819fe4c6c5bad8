"""Dispersed Monte Carlo studies: specs parsed (and refused) with clear messages, drawn
values stored in every row and reproducible from the realization's seed, and each
realization scored against the truth of its own dispersed aircraft."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.scenarios import montecarlo
from flightid.scenarios.cards import load_card
from flightid.scenarios.montecarlo import disperse

CARD = "navion-demo"
SPECS = ("derivative_delta[derivative=Cm_alpha]:0.05", "mass_scale:0.05:uniform",
         "bias[channel=q]:0.001")


def test_specs_parse_with_neutral_values_and_defaults():
    d = disperse.parse("mass_scale:0.05")
    assert (d.effect, d.parameter, d.width, d.distribution) == ("mass_scale", "factor", 0.05,
                                                                  "normal")
    assert d.neutral == 1.0 and d.key == "mass_scale.factor"
    d = disperse.parse("derivative_delta[derivative=Cm_alpha].delta:0.1:uniform")
    assert d.key == "derivative_delta[derivative=Cm_alpha].delta" and d.neutral == 0.0
    assert disperse.parse(d.text()) == d
    # uniform draws stay within the half-width around the neutral value; normal ones have
    # the asked standard deviation (4000 draws: its sampling error is about 1.1 %)
    rng = np.random.default_rng(0)
    u = np.array([disperse.parse("inertia_scale.iyy:0.1:uniform").draw(rng)
                  for _ in range(4000)])
    assert u.min() >= 0.9 and u.max() <= 1.1
    g = np.array([disperse.parse("cg_offset.x:0.02").draw(rng) for _ in range(4000)])
    assert abs(g.mean()) < 4 * 0.02 / np.sqrt(4000)
    assert g.std() == pytest.approx(0.02, rel=0.05)


@pytest.mark.parametrize("spec, message", [
    ("mass_scale", "expected EFFECT"),
    ("massscale:0.05", "unknown effect 'massscale'"),
    ("inertia_scale:0.05", "name one"),
    ("mass_scale.iyy:0.05", "no sizing parameter 'iyy'"),
    ("mass_scale:-1", "width must be > 0"),
    ("mass_scale:0.1:gamma", "distribution 'gamma'"),
    ("bias:0.001", "needs its channel"),
    ("derivative_delta[derivative=Cm_foo]:0.1", "derivative must be one of"),
    ("turbulence:0.1", "only airframe, actuator and sensor"),
])
def test_bad_specs_are_refused_by_name(spec, message):
    with pytest.raises(ValueError, match=message):
        disperse.parse(spec)


def test_a_sensor_channel_the_card_lacks_is_refused_before_flying(tmp_path):
    with pytest.raises(ValueError, match="no sensor channel 'rpm2'"):
        montecarlo.run(CARD, 2, "ee", "lon", study_dir=tmp_path / "s", workers=1,
                       disperse=["bias[channel=rpm2]:0.1"])
    card = load_card(CARD)
    values = {"bias[channel=q].value": 0.25}
    flown = disperse.dispersed_card(card, disperse.parse_all(["bias[channel=q]:0.1"]), values)
    assert flown.sensors.channels["q"][0].value == 0.25
    assert flown.sensors.channels["q"][1:] == card.sensors.channels["q"]
    assert card.sensors.channels["q"][0] != flown.sensors.channels["q"][0]  # not mutated


def test_dispersed_study_stores_draws_and_scores_against_the_dispersed_truth(tmp_path):
    folder = tmp_path / "dispersed"
    summary = montecarlo.run(CARD, 3, "ee", "lon", study_dir=folder, workers=2,
                             report=False, disperse=SPECS)
    df = montecarlo.load(folder)
    assert summary.realizations == 3 and summary.failures == 0
    cols = [f"disperse:{disperse.parse(s).key}" for s in SPECS]
    assert set(cols) <= set(df.columns)
    per = df.groupby("index")
    for col in cols:
        assert (per[col].nunique() == 1).all()  # one draw per realization, in every row
        assert df.groupby("index")[col].first().nunique() == 3  # different draws
    # the draws come from the realization's seed alone
    specs = disperse.parse_all(SPECS)
    for _, rows in per:
        drawn = disperse.draw(specs, int(rows["seed"].iloc[0]))
        for key, value in drawn.items():
            assert rows[f"disperse:{key}"].iloc[0] == value
    mass = df.groupby("index")["disperse:mass_scale.factor"].first()
    assert ((mass >= 0.95) & (mass <= 1.05)).all()
    # Cm_alpha's truth is the aircraft's plus the drawn delta: truth - delta is the same
    # for every realization (to the truth linearization's step error, 1e-5 per rad; the
    # mass draw moves the trim but the Navion's Cm is linear in alpha), while the truth
    # itself moves by the draws (sigma 0.05 per rad)
    cm = df[df["name"] == "Cm_alpha"].set_index("index")
    delta = cm["disperse:derivative_delta[derivative=Cm_alpha].delta"]
    assert np.ptp(cm["truth"] - delta) < 1e-5
    assert np.ptp(cm["truth"]) > 1e-3
    np.testing.assert_allclose(cm["error"], cm["estimate"] - cm["truth"], atol=1e-12)
    row = summary.row("Cm_alpha")
    assert row.bias == pytest.approx(float(cm["error"].mean()))
    assert row.truth == pytest.approx(float(cm["truth"].mean()))
    # another dispersion is another study
    with pytest.raises(montecarlo.StudyMismatch, match="disperse"):
        montecarlo.run(CARD, 3, "ee", "lon", study_dir=folder, workers=1,
                       disperse=SPECS[:2])


def test_command_line_refuses_a_bad_dispersion_with_exit_2(tmp_path):
    bad = tmp_path / "d.toml"
    bad.write_text('disperse = "mass_scale:0.05"\n')
    for args, message in (
            (["--disperse", "massscale:0.1"], "unknown effect 'massscale'"),
            (["--disperse-file", str(bad)], "expected disperse = ["),
    ):
        result = CliRunner().invoke(app, ["montecarlo", CARD, "-n", "2", "-o",
                                          str(tmp_path / "s"), "--quiet", *args])
        assert result.exit_code == 2, result.output
        assert message in result.output
