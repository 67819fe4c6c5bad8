"""Augmented aircraft (flightid.sim.augment): effects written into a copy of a JSBSim XML.

- derivative deltas show up exactly in the numerical truth (issue 24: Cn_beta -0.4/rad and
  Cl_beta -0.1/rad into the stock DHC6) and the XML loads in plain jsbsim;
- an actuator rate limit of 20 deg/s clips the Navion's elevator 3211 (docs/img/rate_limit.png);
- cards inject them with [[effect]] and the record names what was injected.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import textwrap
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from flightid.scenarios.cards import CardError, card_from_dict, fly_card, load_card
from flightid.sim.augment import augment
from flightid.sim.effects.airframe import DerivativeDelta, RateLimit
from flightid.sim.flight import disturbed as dist
from flightid.sim.flight.controls import hold_center
from flightid.sim.flight.simulation import Simulation, fly
from flightid.sim.jsbsim.model import PACKAGE_AIRCRAFT, load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives
from flightid.units import DEG

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

IMG = Path(__file__).resolve().parents[2] / "docs" / "img" / "rate_limit.png"


def _value(truth, name: str) -> float:
    """A truth derivative (the central slope where truth flags a kink)."""
    return truth.values[name] if name in truth.values else truth.flags[name].central


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize("axes", ["stability", "body"])
def test_dhc6_derivative_deltas_show_up_exactly_in_truth(tmp_path, axes):
    original = PACKAGE_AIRCRAFT / "DHC6" / "DHC6.xml"
    before = _sha(original)
    deltas = {"Cn_beta": -0.4, "Cl_beta": -0.1}
    xml = augment("DHC6", [DerivativeDelta(derivative=k, delta=v, axes=axes)
                           for k, v in deltas.items()], tmp_path)
    assert _sha(original) == before  # the original is untouched
    assert xml == tmp_path / "aircraft" / "DHC6-augmented" / "DHC6-augmented.xml"
    text = xml.read_text(encoding="utf-8")
    assert "derivative_delta Cn_beta -0.4 per rad" in text  # says what was added and why
    base, aug = load("DHC6"), load(str(xml))
    assert aug.name == "DHC6-augmented" and aug.origin == "file"
    t0, t1 = trim(base, 1920.0, 72.3), trim(aug, 1920.0, 72.3)
    d0, d1 = derivatives(base, t0, axes=axes), derivatives(aug, t1, axes=axes)
    for name, delta in deltas.items():
        moved = _value(d1, name) - _value(d0, name)
        assert moved == pytest.approx(delta, rel=0.01), (name, moved)
    # the rest of the aircraft is unchanged (same trim)
    assert t1.alpha == pytest.approx(t0.alpha, abs=1e-9)
    assert _value(d1, "Cm_alpha") == pytest.approx(_value(d0, "Cm_alpha"), rel=1e-9)


def test_even_form_moves_the_one_sided_slopes_apart(tmp_path):
    """``form = "even"`` writes delta x abs(beta): the one-sided slopes move by -delta and
    +delta and the central one stays. The stock DHC6's Clb table is even in beta at low
    alpha (slopes -0.42 / +0.40 per rad); the even term of minus half their difference
    leaves two equal one-sided slopes, the kink gone (what the gap diagnosis writes)."""
    base = load("DHC6")
    t0 = trim(base, 1890.0, 72.2)
    kink = derivatives(base, t0, axes="body").flags["Cl_beta"]
    even = 0.5 * (kink.plus - kink.minus)
    assert even == pytest.approx(0.036 / np.radians(5.0), rel=0.05)  # the table's 0.036
    xml = augment("DHC6", [DerivativeDelta(derivative="Cl_beta", delta=-even, axes="body",
                                           form="even")], tmp_path)
    assert "x abs(variable)" in xml.read_text(encoding="utf-8")
    aug = load(str(xml))
    d1 = derivatives(aug, trim(aug, 1890.0, 72.2), axes="body")
    assert "Cl_beta" not in d1.flags  # no kink left: one slope on both sides
    assert d1.values["Cl_beta"] == pytest.approx(kink.central, abs=2e-3)
    with pytest.raises(ValueError, match="form"):
        DerivativeDelta(derivative="Cl_beta", form="odd")


def test_augmented_xml_loads_in_plain_jsbsim(tmp_path):
    augment("DHC6", [DerivativeDelta(derivative="Cn_beta", delta=-0.4),
                     RateLimit(rate=20 * DEG, surface="de")], tmp_path)
    code = textwrap.dedent(f"""
        import sys, jsbsim
        fdm = jsbsim.FGFDMExec(root_dir={str(tmp_path)!r})
        fdm.set_debug_level(0)
        assert fdm.load_model("DHC6-augmented")
        fdm["ic/h-sl-ft"] = 6000; fdm["ic/vc-kts"] = 120
        assert fdm.run_ic()
        for _ in range(100):
            fdm.run()
        assert "flightid" not in sys.modules
        assert "aero/augment/Cn_beta" in fdm.query_property_catalog("aero/augment")
        print("ok", fdm["fcs/augment/elevator-actuator"])
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "ok" in out.stdout


def _3211(t: np.ndarray, start: float, pulse: float, amplitude: float) -> np.ndarray:
    edges = start + pulse * np.cumsum([0, 3, 2, 1, 1])
    out = np.zeros_like(t)
    for i, sign in enumerate((1, -1, 1, -1)):
        out[(t >= edges[i]) & (t < edges[i + 1])] = sign * amplitude
    return out


def test_rate_limit_clips_the_navion_elevator_3211(tmp_path):
    rate, duration = 100.0, 6.0
    t = np.arange(int(duration * rate) + 1) / rate
    controls = {"de": _3211(t, 1.0, 0.3, 5 * DEG)}
    xml = augment("navion", [RateLimit(surface="de", rate=20 * DEG)], tmp_path)

    def fly(aircraft: str):
        model = load(aircraft)
        return dist.fly_disturbed(model, trim(model, 500.0, 53.64), controls, duration, rate,
                                  dist.atmosphere_for([], 1))

    free, limited = fly("navion"), fly(str(xml))
    max_free = np.max(np.abs(np.diff(free["de"]))) * rate / DEG
    max_limited = np.max(np.abs(np.diff(limited["de"]))) * rate / DEG
    assert max_limited == pytest.approx(20.0, rel=0.02)
    assert max_free > 40.0  # the Navion's own actuator: lag 20/s, 60 deg/s
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 5.5))
    trim_de = free["de"][0] / DEG
    ax1.plot(t, trim_de + controls["de"] / DEG, "k:", lw=1, label="commanded 3211")
    ax1.plot(t, free["de"] / DEG, label=f"navion (max {max_free:.0f} deg/s)")
    ax1.plot(t, limited["de"] / DEG, label=f"rate_limit 20 deg/s (max {max_limited:.1f} deg/s)")
    ax1.set_ylabel("de (deg)")
    ax1.legend(fontsize=8)
    ax1.set_title("Navion elevator 3211 (5 deg, 0.3 s pulses): actuator rate limit injected")
    ax2.plot(t, free["q"] / DEG, label="navion")
    ax2.plot(t, limited["q"] / DEG, label="with rate limit")
    ax2.set_ylabel("q (deg/s)")
    ax2.set_xlabel("t (s)")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    IMG.parent.mkdir(exist_ok=True)
    fig.savefig(IMG, dpi=90)
    plt.close(fig)


CARD = """\
aircraft = "navion"
duration = 3.0
[condition]
altitude = 500.0
speed = 53.64
[[maneuver]]
kind = "doublet"
surface = "de"
start = 0.2
amplitude_deg = 3.0
base = 0.4
[[effect]]
name = "rate_limit"
surface = "de"
rate_deg = 20
[[effect]]
name = "derivative_delta"
derivative = "Cm_q"
delta = -2.0
"""


def test_card_flies_the_augmented_aircraft_and_names_the_injection(tmp_path):
    path = tmp_path / "aug.toml"
    path.write_text(CARD, encoding="utf-8")
    card = load_card(path)
    assert card.effects == {"effect[0]": "rate_limit", "effect[1]": "derivative_delta"}
    assert card.augmentation[0] == RateLimit(surface="de", rate=20 * DEG)
    _, truth = fly_card(card)
    injected = truth.meta.extra["injected"]
    assert injected["aircraft"] == "navion"
    assert injected["effects"][0] == {"name": "rate_limit", "surface": "de",
                                      "rate": pytest.approx(20 * DEG)}
    assert injected["effects"][1]["delta"] == -2.0
    assert np.max(np.abs(np.diff(truth["de"]))) * card.rate / DEG == pytest.approx(20, rel=0.02)
    plain = card_from_dict({k: v for k, v in card.data.items() if k != "effect"})
    _, clean = fly_card(plain)
    assert "injected" not in clean.meta.extra
    assert not np.allclose(clean["q"], truth["q"])


@pytest.mark.parametrize("table, field, match", [
    ('name = "rate_limit"\nsurface = "dx"', "effect[0]", "surface"),
    ('name = "rate_limit"\nrate_deg = -3', "effect[0].rate", "outside the allowed range"),
    ('name = "noise"', "effect[0].name", "is a sensor effect"),
    ('name = "nope"', "effect[0].name", "unknown airframe or actuator effect"),
    ('name = "derivative_delta"\nderivative = "Cx_beta"', "effect[0]", "derivative"),
])
def test_card_effect_errors_name_file_line_and_field(tmp_path, table, field, match):
    text = CARD.split("[[effect]]")[0] + "[[effect]]\n" + table + "\n"
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(CardError, match=match) as err:
        load_card(path)
    assert err.value.path == str(path)
    assert err.value.line is not None and err.value.line >= 12
    assert err.value.field.startswith(field)


@pytest.mark.parametrize("aircraft", ["navion", "telemaster", "twinotter", "DHC6"])
def test_surface_drive_sets_positions_past_the_fcs(tmp_path, aircraft):
    """``surface_drive=True``: with the drive off the aircraft flies exactly as the plain
    one (same flight, bit for bit); with ``surfaces="driven"`` the recorded surfaces are
    the driven positions exactly (no actuator lag), on every aircraft, a stock one too."""
    speed = 18.0 if aircraft == "telemaster" else 50.0
    plain = load(aircraft)
    driven = load(str(augment(aircraft, [], tmp_path, surface_drive=True)))
    t = np.arange(301) / 100.0
    de = _3211(t, 0.5, 0.3, 1 * DEG)
    da = np.where((t > 1.0) & (t < 1.5), 2 * DEG, 0.0)
    a = fly(plain, trim(plain, 1000.0, speed), {"de": de, "da": da}, 3.0)
    b = fly(driven, trim(driven, 1000.0, speed), {"de": de, "da": da}, 3.0)
    for ch in ("q", "p", "de", "da", "alpha"):
        np.testing.assert_array_equal(a[ch], b[ch])
    tr = trim(driven, 1000.0, speed)
    c = fly(driven, tr, {"de": de, "da": da}, 3.0, surfaces="driven")
    acts = t + hold_center(100.0)  # each sample is written where it acts
    np.testing.assert_allclose(c["de"], tr.elevator + np.interp(acts, t, de), atol=1e-12)
    np.testing.assert_allclose(c["da"], tr.aileron + np.interp(acts, t, da), atol=1e-12)
    if aircraft != "DHC6":  # (the stock DHC6's elevator follows its command at once)
        assert np.max(np.abs(a["de"] - (tr.elevator + de))) > 0.2 * DEG  # the lag, bypassed
    with pytest.raises(ValueError, match="surface_drive=True"):
        Simulation(plain, surfaces="driven")
    with pytest.raises(ValueError, match="surfaces must be one of"):
        Simulation(plain, surfaces="measured")


def test_measured_surfaces_driven_reproduce_the_flight(tmp_path):
    """The positions a flight recorded (through the Twin Otter's 1/20 s actuator), driven
    back into the aircraft at the record's 100 Hz, reproduce its pitch rate to 0.2 % of
    its peak (measured 0.08 %: each sample is written interpolated where it acts, and held
    over the 4 substeps in which the actuator moves); fed as commands, they are lagged a
    second time (27 % off)."""
    model = load(str(augment("twinotter", [], tmp_path, surface_drive=True)))
    tr = trim(model, 1890.0, 61.7)
    t = np.arange(1001) / 100.0
    flown = fly(model, tr, {"de": _3211(t, 1.0, 0.5, 2 * DEG)}, 10.0)
    measured = flown["de"] - flown["de"][0]
    again = fly(model, tr, {"de": measured}, 10.0, surfaces="driven")
    lagged = fly(model, tr, {"de": measured}, 10.0)
    peak = np.max(np.abs(flown["q"]))
    assert np.max(np.abs(again["q"] - flown["q"])) < 0.002 * peak
    assert np.max(np.abs(lagged["q"] - flown["q"])) > 0.1 * peak
