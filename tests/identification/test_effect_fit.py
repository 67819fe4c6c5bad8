"""Effects fitted back by flying the augmented JSBSim aircraft (``identification.effect_fit``).

- issue 24, "done when": an actuator rate limit of 20 deg/s on the Navion elevator visibly
  clips a 3211 of 5 deg and 0.3 s pulses, and is fitted back (docs/img/rate_limit_fit.png);
- the iced Twin Otter's record fitted with the ``tail_ice`` effect on the plain Twin Otter
  gives back the iced ratios (three parameters at once);
- an aileron effect is fitted with the lateral outputs;
- bad input is refused with a message naming what is wrong.

Records carry the research suite's white noise on the compared outputs only, so the bounds
are Cramer-Rao bounds of a correct model (JSBSim is both the truth and the model).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from flightid.identification.effect_fit import LATERAL, fit_effect
from flightid.scenarios.cards import card_from_dict, fly_card
from flightid.scenarios.inputs import input_from_dict, total_signals
from flightid.sim.effects.airframe import ActuatorLag, RateLimit, TailIce
from flightid.sim.effects.sensor import Bias, WhiteNoise
from flightid.sim.sensors.builtin import research_suite
from flightid.units import DEG

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

IMG = Path(__file__).resolve().parents[2] / "docs" / "img" / "rate_limit_fit.png"
OUTPUTS = ("V", "alpha", "q", "theta", "de")
BOUNDS = 3.0


def _card(aircraft: str, condition: dict, maneuver: list, effect: list, duration: float,
          outputs: tuple[str, ...] = OUTPUTS) -> dict:
    suite = research_suite()
    return {"name": "effect-fit", "aircraft": aircraft, "duration": duration, "rate": 50.0,
            "seed": 3, "condition": condition, "maneuver": maneuver, "effect": effect,
            "sensors": {"suite": "research", "drop": ["vanes", "lever_arm"], "channels": {
                c: [e.to_dict() for e in suite.channels[c] if isinstance(e, WhiteNoise)]
                for c in outputs}}}


def _commanded(truth, measured) -> dict[str, np.ndarray]:
    return total_signals([input_from_dict(d) for d in truth.meta.extra["inputs"]],
                         measured.time)


def test_rate_limit_of_20_deg_s_on_the_navion_elevator_is_fitted_back():
    data = _card("navion", {"altitude": 0.0, "speed": 53.64},
                 [{"kind": "3211", "surface": "de", "start": 1.0, "base": 0.3,
                   "amplitude_deg": 5.0}],
                 [{"name": "rate_limit", "surface": "de", "rate_deg": 20.0}], 6.0)
    measured, truth = fly_card(card_from_dict(data))
    plain, _ = fly_card(card_from_dict({k: v for k, v in data.items() if k != "effect"}))
    commanded = _commanded(truth, measured)
    fitted = fit_effect(measured, "navion", RateLimit(surface="de", rate=40 * DEG), ["rate"],
                        controls=commanded, outputs=OUTPUTS)
    rate, std = fitted.values["rate"], fitted.std["rate"]
    assert fitted.estimate.fit["converged"], fitted.estimate.fit["reason"]
    assert abs(rate - 20 * DEG) < BOUNDS * std, (rate / DEG, std / DEG)
    assert std < 0.01 * 20 * DEG  # measured 0.0012 deg/s
    assert fitted.likelihood_ratio > 1000  # the record shows the limit beyond doubt
    # visibly clipped: the limited surface moves at 20 deg/s where the plain one reaches 60
    rate_of = {k: np.max(np.abs(np.diff(r["de"]))) * 50.0 / DEG
               for k, r in (("limited", truth), ("plain", plain))}
    assert rate_of["limited"] == pytest.approx(20.0, rel=0.02)
    assert rate_of["plain"] > 55.0
    model = fitted.estimate.outputs["de"]["model"]
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 5.5))
    t = measured.time
    ax1.plot(t, (plain["de"][0] + commanded["de"]) / DEG, "k:", lw=1, label="commanded 3211")
    ax1.plot(t, plain["de"] / DEG, label=f"navion, no limit (max {rate_of['plain']:.0f} deg/s)")
    ax1.plot(t, measured["de"] / DEG, ".", ms=2.5, label="measured, rate limit 20 deg/s")
    ax1.plot(t, model / DEG, "--", lw=1.2,
             label=f"fitted: {rate / DEG:.2f} +- {std / DEG:.3f} deg/s")
    ax1.set_ylabel("de (deg)")
    ax1.legend(fontsize=8)
    ax1.set_title("Navion elevator 3211 (5 deg, 0.3 s pulses): rate limit injected, fitted back")
    ax2.plot(t, plain["q"] / DEG, label="navion, no limit")
    ax2.plot(t, measured["q"] / DEG, ".", ms=2.5, label="measured, with limit")
    ax2.plot(t, fitted.estimate.outputs["q"]["model"] / DEG, "--", lw=1.2, label="fitted")
    ax2.set_ylabel("q (deg/s)")
    ax2.set_xlabel("t (s)")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    IMG.parent.mkdir(exist_ok=True)
    fig.savefig(IMG, dpi=90)
    plt.close(fig)


def test_tail_ice_fitted_from_the_iced_twin_otter_record():
    """The record flies ``twinotter-iced`` (its own XML); the model is ``twinotter`` plus
    ``tail_ice`` with its three factors free, started at no ice."""
    data = _card("twinotter-iced", {"altitude": 1897.0, "speed": 61.733333},
                 [{"kind": "3211", "surface": "de", "start": 1.0, "base": 0.5,
                   "amplitude_deg": 3.0}], [], 8.0)
    data.pop("effect")
    measured, truth = fly_card(card_from_dict(data))
    fitted = fit_effect(measured, "twinotter", TailIce(elevator=1.0, stability=1.0, damping=1.0),
                        controls=_commanded(truth, measured), outputs=OUTPUTS)
    assert fitted.estimate.fit["converged"], fitted.estimate.fit["reason"]
    for name, iced in {"elevator": 0.85, "stability": 0.9, "damping": 0.9}.items():
        got, std = fitted.values[name], fitted.std[name]
        assert abs(got - iced) < BOUNDS * std, (name, got, std)
        assert std < 0.01, (name, std)


def test_aileron_lag_fitted_with_the_lateral_outputs():
    """A lateral surface: the aileron's lag (the default outputs beta p r phi da dr)."""
    data = _card("navion", {"altitude": 0.0, "speed": 53.64},
                 [{"kind": "doublet", "surface": "da", "start": 0.5, "base": 0.5,
                   "amplitude_deg": 4.0}],
                 [{"name": "actuator_lag", "surface": "da", "tau": 0.1}], 4.0, LATERAL)
    measured, truth = fly_card(card_from_dict(data))
    fitted = fit_effect(measured, "navion", ActuatorLag(surface="da", tau=0.05),
                        controls=_commanded(truth, measured))
    assert fitted.names == ["tau"] and fitted.estimate.fit["converged"]
    assert abs(fitted.values["tau"] - 0.1) < BOUNDS * fitted.std["tau"], fitted.values
    assert fitted.std["tau"] < 0.005


def test_bad_input_is_refused():
    data = _card("navion", {"altitude": 0.0, "speed": 53.64},
                 [{"kind": "doublet", "surface": "de", "start": 0.5, "base": 0.3,
                   "amplitude_deg": 2.0}], [], 2.0)
    data.pop("effect")
    measured, _ = fly_card(card_from_dict(data))
    with pytest.raises(ValueError, match="not an airframe or actuator effect"):
        fit_effect(measured, "navion", Bias(value=0.01))
    with pytest.raises(ValueError, match="no parameter"):
        fit_effect(measured, "navion", RateLimit(), ["tau"])
    with pytest.raises(ValueError, match="lacks output channel"):
        fit_effect(measured, "navion", RateLimit(), outputs=["nope"])
    with pytest.raises(ValueError, match="has shape"):
        fit_effect(measured, "navion", RateLimit(), controls={"de": np.zeros(3)})
    bare = dataclasses.replace(measured, meta=dataclasses.replace(measured.meta, condition={}))
    with pytest.raises(ValueError, match="flight condition"):
        fit_effect(bare, "navion", RateLimit())
