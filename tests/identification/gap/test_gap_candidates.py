"""Every catalogue entry a candidate of the gap diagnosis or listed as not identifiable,
each family named from a real JSBSim flight, physical ranges, and records with fewer
channels (identification/gap/candidates: build, sensor, actuator, mass, identifiable,
ranges).

Each family test flies one card with the effect injected (calm air, research sensors at
50 Hz with their noise and 10 Hz anti-alias filters, the vanes and lever arm corrected to
the CG as in the blind check) and diagnoses it against the plain aircraft without being
told; the injected entry must be named first, its magnitude within a tolerance stated
beside each check (measured values in docs/gap.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flightid.identification.gap import diagnose
from flightid.identification.gap.candidates.build import catalogue_candidates
from flightid.identification.gap.candidates.identifiable import not_identifiable
from flightid.identification.gap.candidates.ranges import out_of_range
from flightid.identification.gap.lines import ENTRY as LINE_ENTRY
from flightid.identification.gap.lines import spectral_line
from flightid.identification.gap.model.linearise import carried_outputs, linearise
from flightid.identification.gap.model.surfaces import run_actuators
from flightid.record import FlightRecord
from flightid.scenarios.cards import card_from_dict, fly_card
from flightid.scenarios.gap_benchmark.cases import AIRCRAFT, Case, Effect
from flightid.scenarios.gap_benchmark.run import fly_case, truths
from flightid.sim.augment.actuators import actuator_chains
from flightid.sim.effects.catalogue import CATALOGUE
from flightid.sim.sensors.builtin import research_suite
from tests.lateral_card import commands, maneuvers

DROPPED = ["vanes", "lever_arm"]  # calibrated to the CG, as the blind check's cards
# the lateral cards' recorded rate: half the blind check's 50 Hz, so that each diagnosis
# takes half the time (the research suite's 10 Hz anti-alias filter is below 12.5 Hz)
OUTPUT_RATE = 25.0


def _lateral(aircraft: str = "navion", effects=(), mounting=None, channels=None):
    """The blind check's lateral card (each surface moved twice, 44 s at 50 Hz)."""
    f = AIRCRAFT[aircraft]
    sensors = ({"suite": "research", "mounting": mounting} if mounting is not None
               else {"suite": "research", "drop": DROPPED})
    sensors["output_rate"] = OUTPUT_RATE
    if channels:  # an effect first in a channel's chain, then the research chain
        sensors["channels"] = {c: [*pre, *(e.to_dict() for e in research_suite().channels[c])]
                               for c, pre in channels.items()}
    data = {"name": "gap-candidates", "aircraft": aircraft, "duration": 44.0, "rate": 50.0,
            "seed": 1, "condition": {"altitude": f.altitude_m, "speed": f.speed_m_s},
            "maneuver": maneuvers(aircraft), "sensors": sensors}
    if effects:
        data["effect"] = list(effects)
    return fly_card(card_from_dict(data))


def _elevator(effects=(), extra=()):
    """The Navion at Teper's condition: an elevator 3211 and a doublet 16 s apart."""
    data = {"name": "gap-candidates-elevator", "aircraft": "navion", "duration": 32.0,
            "rate": 100.0, "seed": 1, "condition": {"altitude": 0.0, "speed": 53.645},
            "maneuver": [{"kind": "3211", "surface": "de", "start": 2.0, "base": 0.5,
                          "amplitude_deg": 2.0},
                         {"kind": "doublet", "surface": "de", "start": 18.0, "base": 1.0,
                          "amplitude_deg": 2.0}, *extra],
            "sensors": {"suite": "research", "output_rate": 20.0, "drop": DROPPED}}
    if effects:
        data["effect"] = list(effects)
    measured, _ = fly_card(card_from_dict(data))
    return measured


def _without(record: FlightRecord, *names: str) -> FlightRecord:
    return FlightRecord(record.time, {k: v for k, v in record.channels.items()
                                      if k not in names}, record.meta)


def _diagnosed(record, aircraft="navion", axis="lateral", **kw):
    return diagnose([record], aircraft, axis=axis, try_pairs=False, steps=1, **kw)


def _first(result, entry: str, **options: str):
    top = result.named[0]
    assert top.candidate.entry == entry, [r.candidate.label for r in result.effects[:5]]
    for k, v in options.items():
        assert top.candidate.options[k] == v
    return top


# -- every entry: a candidate or not identifiable ----------------------------------------


@pytest.fixture(scope="module")
def hobby():
    """The Telemaster's lateral test (each surface moved twice, 44 s) recorded by the hobby
    suite at 50 Hz (no attitudes; its vanes, lever arm and engine vibration left out) with
    its rudder's effectiveness at 0.6."""
    f = AIRCRAFT["telemaster"]
    data = {"name": "gap-candidates-hobby", "aircraft": "telemaster", "duration": 44.0,
            "rate": 50.0, "seed": 1,
            "condition": {"altitude": f.altitude_m, "speed": f.speed_m_s},
            "maneuver": maneuvers("telemaster"),
            "sensors": {"suite": "hobby", "output_rate": 50.0,
                        "drop": ["vanes", "lever_arm", "engine_vibration"]},
            "effect": [{"name": "control_effectiveness", "surface": "dr", "factor": 0.6}]}
    measured, _ = fly_card(card_from_dict(data))
    return measured


@pytest.mark.parametrize("axis", ["lateral", "longitudinal"])
@pytest.mark.parametrize("surfaces", ["position", "command"])
def test_every_catalogue_entry_is_a_candidate_or_not_identifiable(hobby, axis, surfaces):
    lin = linearise("telemaster", [hobby], axis, surfaces)
    cands = catalogue_candidates(lin.model, lin.axes, surfaces=lin.surfaces)
    listed = not_identifiable(lin.model, [hobby], surfaces=surfaces)
    named = {c.entry for c in cands}
    # engine vibration: a candidate of the spectral-line check on the IMU channels
    if spectral_line([hobby], axis) is not None:
        named.add(LINE_ENTRY)
    assert LINE_ENTRY in named
    keys = {k.partition("(")[0] for k in listed}
    assert set(CATALOGUE) <= named | keys, set(CATALOGUE) - named - keys
    assert not named & set(listed), "an entry is a candidate and listed as not identifiable"
    assert all(why for why in listed.values())
    for c in cands:  # the candidate's parameters are the catalogue entry's
        assert c.entry in CATALOGUE
        entry = CATALOGUE[c.entry]
        # options are the entry's, or the channel a sensor entry sits on
        assert set(c.options) <= {o.name for o in entry.options} | {"channel"}
        if c.entry != "derivative_delta":
            assert {p.name for p in entry.parameters} >= set(c.catalogue or ("factor",))
    assert ("actuator_lag" in named) == (surfaces == "command")
    assert "command" in listed.get("actuator_lag", "command")
    assert "bias" in listed and "CL_0" in listed["bias"]
    assert ("tail_ice" in named) == (axis == "longitudinal")
    # derivative deltas and control effectiveness on both axes
    labels = {c.label for c in cands}
    if axis == "longitudinal":
        assert {"derivative_delta(Cm_alpha,stability)", "derivative_delta(CL_alpha,stability)",
                "derivative_delta(CD_alpha,stability)", "control_effectiveness(de)"} <= labels
    else:
        assert {"derivative_delta(Cn_beta,body)", "control_effectiveness(da)",
                "control_effectiveness(dr)", "misalignment(y)"} <= labels


# -- physical ranges ------------------------------------------------------------------------


def test_out_of_range_names_the_family(hobby):
    lin = linearise("telemaster", [hobby], "longitudinal")
    cands = {c.label: c for c in catalogue_candidates(lin.model, lin.axes)}
    tail = cands["tail_ice()"]

    def params(**v):
        return {k: {"value": x, "std": 0.01} for k, x in v.items()}

    assert out_of_range(tail, params(elevator=0.85, stability=0.9, damping=0.9)) is None
    assert out_of_range(tail, params(elevator=1.38, stability=0.9, damping=1.0)) == \
        "horizontal-tail effectiveness (Cm_de) +38 %"
    # a Cm_alphadot delta of +19.7 on a model at -8 (the NASA case): no airframe
    d = cands["derivative_delta(Cm_alphadot,stability)"]
    model = lin.model.with_start(Cm_alphadot=-8.0)
    family = out_of_range(d, {"delta": {"value": 19.7, "std": 1.0}}, model)
    assert family.startswith("Cm_alphadot +11.7 is outside [-30, 5]") and "lag" in family
    assert out_of_range(d, {"delta": {"value": 1.0, "std": 1.0}}, model) is None
    assert "leads the model" in out_of_range(cands["delay(q)"], params(tau=-0.02))
    assert out_of_range(cands["scale(q)"], params(factor=1.1)) is None
    # the inertia scale within [0.7, 1.45] (the seed-10 rules): seed 9's misses fitted Iyy
    # 1.46-1.72 where the tail's effectiveness was injected; the right ones 1.22 and 1.30
    inertia = cands["inertia_scale()"]
    assert out_of_range(inertia, params(iyy=1.30)) is None
    assert out_of_range(inertia, params(iyy=1.72)) == (
        "the pitching-moment derivatives scaled by 0.581, not an inertia error")
    assert out_of_range(inertia, params(iyy=0.64)) is not None


def test_tail_more_effective_than_the_model_is_not_named_ice():
    """An elevator 30 % more effective than the model's: tail ice fits it with an elevator
    factor above 1, outside (0, 1]; it is not confirmed and names the family, and the
    control effectiveness of the elevator is named."""
    result = _diagnosed(_elevator([{"name": "control_effectiveness", "surface": "de",
                                    "factor": 1.3}]), axis="longitudinal")
    top = _first(result, "control_effectiveness", surface="de")
    # 15 %: the linearised model leaves the changes 7-10 % short (docs/gap.md)
    assert abs(top.parameters["factor"]["value"] - 1.3) < 0.15 * 0.3
    tail = next(r for r in result.effects if r.candidate.entry == "tail_ice")
    assert not tail.confirmed and tail.family.startswith("horizontal-tail effectiveness")
    assert tail.note.startswith("outside its physical range")
    assert tail.to_json()["family"] == tail.family


# -- fewer channels ------------------------------------------------------------------------


def test_hobby_record_diagnosed_on_the_outputs_it_has(hobby):
    """The hobby suite records no attitudes: the lateral model drops phi (every state
    kept), and the rudder's effectiveness loss ranks first from beta, p, r and ay. It is
    not confirmed: the hobby sensors' 8-bit noise leaves it a held-out shrink of some 5 %
    (measured at 100 Hz: factor 0.496, shrink 0.055), under the 10 % that confirms."""
    assert "phi" not in hobby and "beta" in hobby
    result = _diagnosed(hobby, "telemaster")
    assert result.linearised.model.outputs == ("beta", "p", "r", "ay")
    assert "phi" in result.linearised.model.states
    top = result.effects[0]
    assert top.candidate.label == "control_effectiveness(dr)"
    factor = top.parameters["factor"]
    # within 3 of its (colored-residual) bounds, or 0.15 of the 0.4 change
    assert abs(factor["value"] - 0.6) < max(3 * factor["std"], 0.15)
    assert set(result.where.by_channel()) == {"beta", "p", "r", "ay"}
    no_vanes = _without(hobby, "beta", "alpha")
    assert carried_outputs([no_vanes], "lateral") == ("p", "r", "ay")
    with pytest.raises(ValueError, match="missing beta, p, phi, ay"):
        carried_outputs([_without(hobby, "beta", "p", "ay")], "lateral")


# -- each family named from a flight ----------------------------------------------------------


@pytest.mark.parametrize("entry", ["delay", "lag"])
def test_sensor_delay_and_lag_named(entry):
    """0.05 s on the roll-rate gyro (delay) or the yaw-rate gyro (lag), before the research
    chain. Measured: delay(p) 0.0509 s, lag(r) 0.0475 s, each ahead of the other member of
    its class (delay and lag are 1 - tau s in the rigid-body band, docs/gap.md). 10 %: the
    Pade delay is exact to (omega tau)^3 / 12, under 0.1 % at the Dutch roll, and the
    linearised model's own misfit moves a 0.05 s constant by a few ms."""
    channel = "p" if entry == "delay" else "r"
    measured, _ = _lateral(channels={channel: [{"effect": entry, "tau": 0.05}]})
    top = _first(_diagnosed(measured), entry, channel=channel)
    assert abs(top.parameters["tau"]["value"] - 0.05) < 0.1 * 0.05


def test_imu_misalignment_named():
    """The IMU triad rotated 0.08 rad about body y (p and r mixed). Measured 0.0819 rad
    (at 0.06 rad the fitted 0.062 shrank the held-out gap 39 % but by 0.0018 of the
    measured energy, under the 0.002 that confirms)."""
    measured, _ = _lateral(mounting=[{"effect": "misalignment", "axis": "y", "angle": 0.08}])
    top = _first(_diagnosed(measured), "misalignment", axis="y")
    # 10 %: the rotation is exact in the model; the rest is the linearisation's misfit
    assert abs(top.parameters["angle"]["value"] - 0.08) < 0.1 * 0.08


def test_lever_arm_named():
    """Accelerometers 0.5 m ahead of and 0.3 m below the CG. Measured x 0.451, z 0.297 m:
    the tangential terms come from the model's own rdot and pdot, whose linearisation misfit
    shows in the x term (rdot is small in these maneuvers); 0.1 m and 0.05 m."""
    measured, _ = _lateral(mounting=[{"effect": "lever_arm", "x": 0.5, "z": 0.3}])
    top = _first(_diagnosed(measured), "lever_arm")
    assert abs(top.parameters["x"]["value"] - 0.5) < 0.1
    assert abs(top.parameters["z"]["value"] - 0.3) < 0.05


def test_beta_vane_position_named():
    """A sideslip vane 4.5 m ahead of the CG (the research suite's position). Measured
    beta_x 4.23 m, ahead of a 0.068 s beta lag (its near-equivalent, docs/gap.md). 10 %:
    the vane's rotation term is exact to first order; the linearised r is the misfit."""
    measured, _ = _lateral(mounting=[{"effect": "vanes", "beta_x": 4.5}])
    top = _first(_diagnosed(measured), "vanes")
    assert abs(top.parameters["beta_x"]["value"] - 4.5) < 0.1 * 4.5


def test_actuator_lag_named_on_commands_only():
    """A 0.1 s rudder lag on the Telemaster (its own actuators: 0.025 s, run on the
    commands before the model). On the record of commands the rudder's lag is named;
    measured 0.0988 +- 0.0002 s (0.1088 s before the commands ran through the aircraft's
    own actuator model). 3 %: the fitted lag acts after the model's own, a first-order
    stand-in for the injected lag in series. On the same flight's positions the actuator
    has acted on what was recorded: no actuator candidate."""
    measured, truth = _lateral("telemaster", effects=[{"name": "actuator_lag", "surface": "dr",
                                                       "tau": 0.1}])
    result = _diagnosed(commands(measured, truth, ("da", "dr")), "telemaster")
    assert result.linearised.surfaces == "command"
    top = _first(result, "actuator_lag", surface="dr")
    assert abs(top.parameters["tau"]["value"] - 0.1) < 0.03 * 0.1
    lin = linearise("telemaster", [measured], "lateral")
    assert lin.surfaces == "position"
    assert "actuator_lag" not in {c.entry for c in catalogue_candidates(lin.model)}


def test_elevator_lag_in_turbulence_is_not_screened_out():
    """The blind check's seed-0 case 140: a c172p elevator lag of 0.130 s on a record of
    commands, light turbulence. Two Gauss-Newton steps from the lag's start left its delta
    BIC at +185 (21st of the screened candidates, out of the twelve kept), and the axis was
    named ``rate_limit(de)``; evaluated in full (``rank.UNSCREENED``) it is named first,
    measured 0.126 +- 0.027 s: within two of its standard errors (Cramer-Rao, colored
    residual) of the injected value."""
    case = Case(140, 591895872, "c172p", "single", (Effect(
        "actuator_lag", "longitudinal", "card", {"surface": "de"},
        {"tau": 0.1303212573277547}),))
    record = fly_case(case, "light", truths(("c172p",))["c172p"])
    result = diagnose([record], "c172p", axis="longitudinal")
    top = _first(result, "actuator_lag", surface="de")
    tau = top.parameters["tau"]
    assert abs(tau["value"] - 0.1303) < 2 * tau["std"]


def test_cg_offset_named_in_its_class():
    """A CG 0.1 m forward on the Navion's elevator card. A CG shift and a Cm_alpha delta
    are one class (``gap.classes``): Cm_alpha moves by -CL_alpha x/cbar, the other Cm
    terms by under 1 %. The delta is named unless the CG shift is better on held-out data
    by the 10 % margin; here it is (it leaves 2.1 % of the held-out gap, the delta 2.7 %):
    measured x 0.1036 m, the delta -0.249 second. Either member counts, its magnitude as
    the shift it means. 15 % of the shift: the linearised model leaves changes 7-10 %
    short (docs/gap.md)."""
    result = _diagnosed(_elevator([{"name": "cg_offset", "x": 0.1}]), axis="longitudinal")
    top = result.named[0]
    labels = [r.candidate.label for r in result.effects[:3]]
    assert top.candidate.entry == "cg_offset" or top.candidate.options.get(
        "derivative") == "Cm_alpha", labels
    lin = result.linearised
    by = {r.candidate.entry: r for r in result.effects}
    delta = next(r for r in result.effects
                 if r.candidate.options.get("derivative") == "Cm_alpha")
    x_of_delta = -delta.parameters["delta"]["value"] * lin.model.condition.chord / \
        lin.derivatives["CL_alpha"]
    for x in (by["cg_offset"].parameters["x"]["value"], x_of_delta):
        assert abs(x - 0.1) < 0.15 * 0.1


@pytest.mark.parametrize(("entry", "values", "parameter", "injected"), [
    ("mass_scale", {"factor": 1.2}, "factor", 1.2),
    ("inertia_scale", {"ixx": 1.0, "iyy": 1.2, "izz": 1.0}, "iyy", 1.2),
])
def test_mass_properties_named(entry, values, parameter, injected):
    """On the Navion's elevator card. Measured: mass factor 1.189 (a CL_alpha delta
    second), iyy 1.180 (tail ice with all three factors near 1/1.2, its equivalent, not
    confirmed by the nested rule). 15 % of the change: the linearised model leaves
    changes 7-10 % short (docs/gap.md)."""
    result = _diagnosed(_elevator([{"name": entry, **values}]), axis="longitudinal")
    top = _first(result, entry)
    assert abs(top.parameters[parameter]["value"] - injected) < 0.15 * abs(injected - 1.0)


@pytest.mark.parametrize("aircraft", ["telemaster", "navion"])
def test_plain_command_record_is_at_the_null_level(aircraft):
    """The plain aircraft flown on its own commands, the record holding the commands: the
    diagnosis runs them through the aircraft's own actuators (lag and rate limit from its
    XML, the commands held at the card's 50 Hz as the flight set them), so there is no
    gap. Before, with the lags alone in the linear model, both were 'unexplained' (a
    0.0084 s aileron lag ranked first on the Telemaster; the Navion's 60 deg/s limit is
    reached by its 4 deg doublets)."""
    measured, truth = _lateral(aircraft)
    result = _diagnosed(commands(measured, truth, ("da", "dr")), aircraft)
    assert result.linearised.surfaces == "command"
    assert result.verdict == "no_gap", {c: (t.p_value, t.share)
                                        for c, t in result.null_before.channels.items()}
    # the input-explained shares (measured below 0.0003 on every channel) against the null
    # test's materiality of 0.005 of a channel's energy
    assert max(t.share for t in result.null_before.channels.values()) < 0.005 / 5


def test_actuators_run_as_jsbsim_runs_them():
    """A 4 deg aileron step through the Navion's actuator (lag 0.05 s, 60 deg/s): a ramp at
    the rate limit, then the lag's tail; a 0.2 deg step (never rate-limited) is the lag's
    exponential, to the Tustin rule's error: the trapezoid takes the step as a ramp over
    its first 1/400 s step, at most h / (2 tau) = 2.5 % of the step (measured 2.4 %, at
    the first sample, then decaying)."""
    (act,) = actuator_chains("navion")["da"]
    assert (act.tau, math.degrees(act.rate_limit)) == pytest.approx((0.05, 60.0))
    t = np.arange(0.0, 1.0, 0.02)
    big = run_actuators(t, np.where(t >= 0.1, math.radians(4.0), 0.0), [act], rate_hz=50.0)
    slope = np.max(np.diff(big)) / 0.02
    assert slope == pytest.approx(act.rate_limit, rel=1e-6)
    assert big[-1] == pytest.approx(math.radians(4.0), rel=1e-4)
    small = run_actuators(t, np.where(t >= 0.1, math.radians(0.2), 0.0), [act], rate_hz=50.0)
    # set before the last of the 8 internal steps that end at 0.1 s: starts at 0.1 - 1/400
    start = 0.1 - 1.0 / 400.0
    lag = math.radians(0.2) * (1.0 - np.exp(-np.clip(t - start, 0.0, None) / act.tau))
    assert np.max(np.abs(small - lag)) < 0.025 * math.radians(0.2)
    assert np.abs(small - lag)[-1] < 1e-6 * math.radians(0.2)
