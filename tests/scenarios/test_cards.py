"""Flight cards: validation with file/line/field, purity of fly_card, the card library."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from flightid.record import read
from flightid.scenarios.cards import CardError, fly_card, library_cards, load_card
from flightid.sim.flight.simulation import DepartureError
from flightid.units import DEG

BASE = """\
name = "t"
aircraft = "navion"
duration = 12.0
rate = 50.0
seed = 3

[condition]
altitude = 500.0
speed = 53.64

[[maneuver]]
kind = "3211"
surface = "de"
start = 1.0
base = 0.4
amplitude_deg = 2.0
"""
SENSORS = """
[sensors]
suite = "research"
"""
PILOT = """
[[maneuver]]
kind = "bank_to_bank"
start = 4.0
lead = 0.5
trail = 0.5
hold = 0.5
roll_time = 0.5
amplitude_deg = 4.0
"""
TURBULENCE = """
[[disturbance]]
kind = "turbulence"
intensity = "light"
"""


def _card(tmp_path, text, name="card.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_same_card_and_seed_give_identical_files(tmp_path):
    card = load_card(_card(tmp_path, BASE + PILOT + SENSORS + TURBULENCE))
    files = []
    for i in range(2):
        measured, truth = fly_card(card, seed=11)
        files.append((measured.write(tmp_path / f"m{i}.parquet").read_bytes(),
                      truth.write(tmp_path / f"t{i}.parquet").read_bytes()))
    assert files[0] == files[1]
    back = read(tmp_path / "m0.parquet")
    assert back.meta.scenario["seed"] == 11
    assert back.meta.scenario["card"]["maneuver"][0]["kind"] == "3211"


def test_other_seeds_change_only_the_random_parts(tmp_path):
    calm = load_card(_card(tmp_path, BASE + SENSORS))
    m1, t1 = fly_card(calm, seed=1)
    m2, t2 = fly_card(calm, seed=2)
    for name in t1.channels:  # no turbulence, no pilot: the truth is deterministic
        np.testing.assert_array_equal(t1[name], t2[name], err_msg=name)
    assert not np.array_equal(m1["q"], m2["q"])  # sensor noise
    # the noise is the research suite's: q noise 0.0061 deg/s (4-pole anti-alias first)
    assert np.std(m1["q"] - m2["q"]) < 10 * 0.0061 * DEG * np.sqrt(2)

    rough = load_card(_card(tmp_path, BASE + PILOT + TURBULENCE, "rough.toml"))
    _, r1 = fly_card(rough, seed=1)
    _, r2 = fly_card(rough, seed=2)
    # the scripted 3211 is the same, the pilot's aileron and the turbulence are not
    np.testing.assert_array_equal(r1["de"], r2["de"])
    assert not np.array_equal(r1["da"], r2["da"])
    assert not np.array_equal(r1["turb_w"], r2["turb_w"])
    # the seed's default is the card's
    np.testing.assert_array_equal(fly_card(rough)[1]["turb_w"], fly_card(rough, 3)[1]["turb_w"])


def test_card_is_picklable_and_flies_after_a_round_trip(tmp_path):
    card = load_card(_card(tmp_path, BASE + PILOT + SENSORS))
    again = pickle.loads(pickle.dumps(card))
    a, b = fly_card(card, 5)[0], fly_card(again, 5)[0]
    np.testing.assert_array_equal(a["p"], b["p"])


BAD = [
    # (what, replace this, by this, the line that must be named, field)
    ("unknown field", "rate = 50.0", 'rate = 50.0\ncolour = "red"', 'colour = "red"', "colour"),
    ("wrong type", "duration = 12.0", 'duration = "long"', "duration", "duration"),
    ("unknown aircraft", 'aircraft = "navion"', 'aircraft = "concorde"', "concorde",
     "aircraft"),
    ("unknown maneuver kind", 'kind = "3211"', 'kind = "4321"', "4321", "maneuver[0].kind"),
    ("maneuver outside the flight", "start = 1.0", "start = 10.0", "start = 10.0",
     "maneuver[0].start"),
    ("bad maneuver field", "amplitude_deg = 2.0", 'amplitude_deg = "big"', "big",
     "maneuver[0].amplitude_deg"),
    ("bad condition field", "speed = 53.64", "speed = 53.64\nmach = 0.2", "mach",
     "condition.mach"),
    ("TOML syntax", "rate = 50.0", "rate = = 50.0", "rate = =", None),
]


@pytest.mark.parametrize("what,old,new,at,field", BAD, ids=[b[0] for b in BAD])
def test_malformed_cards_name_file_line_and_field(tmp_path, what, old, new, at, field):
    assert old in BASE
    text = BASE.replace(old, new, 1)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if at in s)
    path = _card(tmp_path, text)
    with pytest.raises(CardError) as info:
        load_card(path)
    err = info.value
    assert err.path == str(path) and err.line == line and err.field == field, str(err)
    assert f"{path}:{line}" in str(err)


def test_bad_sensor_effect_and_disturbance_are_located(tmp_path):
    text = BASE + SENSORS + '\n[sensors.channels]\nq = [{effect = "fuzz", sigma = 1.0}]\n'
    with pytest.raises(CardError) as info:
        load_card(_card(tmp_path, text))
    assert info.value.field == "sensors.channels.q[0].effect"
    assert info.value.line == text.splitlines().index("q = [{effect = \"fuzz\", sigma = 1.0}]") + 1
    assert "unknown effect 'fuzz'" in str(info.value)
    text = BASE + SENSORS + '\n[[disturbance]]\nkind = "gust"\nstart = 3.0\ngain = 2.0\n'
    with pytest.raises(CardError) as info:
        load_card(_card(tmp_path, text, "g.toml"))
    assert info.value.field == "disturbance[0].gain"
    assert info.value.line == len(text.splitlines())


def test_unknown_card_lists_the_library():
    with pytest.raises(CardError, match="navion-demo"):
        load_card("no-such-card")


LIBRARY = sorted(library_cards())
# full flights of the heaviest cards are covered by test_simulate and the benchmark; the
# rest fly here end to end (the longest, a 96 s sweep, takes about half a second)


@pytest.mark.parametrize("name", LIBRARY)
def test_library_card_loads_and_flies_without_departing(name):
    card = load_card(name)
    assert card.description and card.source, "library cards say what they are and cite a source"
    try:
        measured, truth = fly_card(card)
    except DepartureError as exc:  # pragma: no cover - the failure message is the point
        pytest.fail(f"{name} departed: {exc}")
    assert truth.time[-1] == pytest.approx(card.duration)
    assert np.all(np.abs(truth["alpha"]) < 15 * DEG)
    assert np.all(np.abs(truth["phi"]) < 45 * DEG)
    assert measured.meta.scenario["name"] == card.name


def test_library_covers_the_seed_flight_tests():
    names = set(LIBRARY)
    assert {"navion-demo", "telemaster-elevator-3211", "telemaster-elevator-doublet",
            "telemaster-elevator-pulse", "navion-sweep-pitch", "navion-sweep-roll",
            "navion-sweep-yaw", "twinotter-21-elevator", "twinotter-lateral-0alpha"} <= names
    demo = load_card("navion-demo")
    assert demo.aircraft == "navion" and demo.condition.altitude_m == 0.0
    assert demo.condition.speed_m_s == pytest.approx(53.64)
    assert {d.surfaces()[0] for d in demo.maneuvers} == {"de", "da", "dr"}
    assert demo.sensors.name == "research" and demo.sensors.output_rate == 50.0
    assert 40.0 <= demo.duration <= 60.0
