"""The database update from a campaign (issue 35 item 3): the library campaign against a
Twin Otter whose Cn_beta falls with airspeed (a derivative_table the model lacks), its
model curve relocated to the flight points (F-111C approach), written as a JSBSim
aircraft, and the held-out points flown again before and after."""

from __future__ import annotations

import json

import pytest

from flightid.scenarios import campaign
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives

# the hidden table: +0.015 at 50 m/s to -0.015 at 75 m/s
SLOPE = -0.03 / 25.0


@pytest.fixture(scope="module")
def updated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("campaign")
    out = tmp_path_factory.mktemp("aircraft")
    return campaign.run("twinotter-hidden-trend", folder, workers=2, update_aircraft=out)


def test_only_cn_beta_is_corrected_with_its_trend(updated):
    kept = {c["name"]: c for c in updated.update["corrections"] if c["form"] != "none"}
    assert list(kept) == ["Cn_beta"]
    c = kept["Cn_beta"]
    assert c["form"] == "shift+slope"
    # measured -0.001153 per m/s for -0.0012 (seed 3: -0.001141): the points' Cn_beta
    # bounds (0.8-1.9e-4) over a 26 m/s span give a slope bound of about 1e-5; the rest
    # is each estimate's structure error (linear in beta over a record whose airspeed
    # moves 2 m/s), so the tolerance is 10 % of the slope
    assert c["slope"] == pytest.approx(SLOPE, rel=0.10)


def test_the_update_shrinks_the_held_out_gap_by_70_percent(updated):
    u = updated.update
    m = u["mean"]
    # the figure: the raw lateral gap of the held-out records, each maneuver window
    # flown as the gap diagnosis re-flies it (start state, surface offsets refitted: the
    # biases and initial conditions of a prediction case). Seed 11, fixed before it was
    # flown: 0.00741 -> 0.00062, 91.7 % (seed 3, where the update was developed: 91.6 %)
    assert u["shrink"]["lateral"] >= 0.70
    # the figure measures the model: what the flown aircraft itself leaves on the same
    # windows (sensor noise, the reduction's errors) is small beside the model's gap
    # (measured 0.00064, 8.6 % of it)
    assert m["floor"]["lateral"] <= 0.2 * m["before"]["lateral"]
    # the model's part of the gap, above that floor: measured 100 %
    assert u["shrink_above_floor"]["lateral"] >= 0.70
    # the whole record flown open loop from the trim, without offsets: the slow modes'
    # drift is a floor of 44 % of the gap (0.0092 of 0.0209), the part above it closes
    o = u["open_loop"]
    assert (o["before"]["lateral"] - o["after"]["lateral"]) >= 0.7 * (
        o["before"]["lateral"] - o["floor"]["lateral"])
    # the derivative itself at the held-out points: RMS error 0.0095 -> 0.00060
    g = u["derivative_gap"]["Cn_beta"]
    assert g["updated"] <= 0.3 * g["model"]
    # the longitudinal gap is not made worse beyond its floor
    assert m["after"]["longitudinal"] <= m["before"]["longitudinal"] + 1e-4
    assert json.loads((updated.folder / campaign.UPDATE).read_text())["effects"]


def test_the_written_aircraft_flies_in_jsbsim_with_the_corrected_table(updated):
    model = load(str(updated.aircraft))
    for speed, truth in ((53.0, 0.015 + SLOPE * 3.0), (72.0, 0.015 + SLOPE * 22.0)):
        value = derivatives(model, trim(model, 1800.0, speed), axes="body").values["Cn_beta"]
        # the model's 0.0864 plus the fitted table: the hidden change (+-0.0114 at these
        # speeds) within 15 % (measured 8 % at 72 m/s, seed 3: 11 %; the slope's 4-7 %
        # over 9 m/s from the points' mean airspeed)
        assert value - 0.08638 == pytest.approx(truth, rel=0.15)


def test_report_shows_the_update(updated):
    text = updated.report.read_text()
    assert "database update: 1 derivative(s) corrected: Cn_beta (shift+slope)" in text
    assert "held-out gap, lateral" in text
