"""The trim-level check of the gap diagnosis (identification/gap/trim_level.py): the
record's steady span against the model's trim at the measured airspeed and altitude.

JSBSim flights of the blind check's card (``scenarios.gap_benchmark.run.fly_case``: the
lateral maneuvers from 2 s, the elevator ones from 42 s, research sensors, light
turbulence unless said), on seeds the development of the thresholds did not use (the
development flew seed 0's null and bias cases). The tolerance of an estimate is its own
bound, ``Z`` sigma: sigma is the standard deviation of the steady mean against the trim
(sensor noise, turbulence and the airspeed's uncertainty through the trim's slope)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from flightid.identification.gap import diagnose
from flightid.identification.gap.model.surfaces import SURFACES_KEY
from flightid.identification.gap.trim_level import (
    CHECKED,
    KINEMATIC,
    KINEMATIC_MATERIAL,
    KINEMATIC_Z,
    MATERIAL,
    Z,
    trim_offsets,
)
from flightid.identification.gap.trim_level import CLASSES as CHECKED_CLASSES
from flightid.scenarios.gap_benchmark.cases import NULL, NULL_INDEX, SINGLE, Case, Effect
from flightid.scenarios.gap_benchmark.classes import CLASSES, classes_of
from flightid.scenarios.gap_benchmark.run import fly_case, run_case, truths

FAST = {"try_pairs": False, "steps": 1}


@pytest.mark.parametrize(("aircraft", "seed", "turbulence"), [
    ("navion", 31, "light"), ("telemaster", 32, "light"), ("c172p", 33, "calm")])
def test_null_flight_names_nothing_at_trim(aircraft, seed, turbulence):
    record = fly_case(Case(NULL_INDEX, seed, aircraft, NULL), turbulence)
    offsets, note = trim_offsets([record], aircraft)
    # the card's first lateral maneuver is at 2 s, too short a span for the sideslip: it is
    # checked on the span from 8 s after the last one (34 s) to the end (64 s)
    assert note == ""
    assert {o.channel for o in offsets} == set(CHECKED) | set(KINEMATIC)
    assert not [o.text() for o in offsets if o.named]
    # in calm air only sensor noise and the lateral maneuvers' load factor move the
    # steady means: every offset below the material level
    if turbulence == "calm":
        assert all(abs(o.difference) < (KINEMATIC_MATERIAL if o.kinematic else MATERIAL)
                   for o in offsets)


@pytest.mark.parametrize(("aircraft", "seed", "angle"), [
    ("twinotter", 35, 0.035), ("telemaster", 36, -0.035)])
def test_imu_pitch_misalignment_named_by_the_kinematic_check(aircraft, seed, angle):
    """An IMU block pitched 2 deg (the catalogue's mounting entry) reads a_x = g sin(theta +
    a): the kinematic check names its class with d = a cos(theta); theta is at most 5 deg
    on these flights (cos > 0.996), and the tolerance is the check's own bound (1.5 sigma:
    measured 0.0248 +- 0.0189 rad on the Twin Otter). The same flight without it names
    nothing there."""
    tilt = Effect("misalignment", "both", "mounting", {}, {"angle": angle})
    record = fly_case(Case(0, seed, aircraft, SINGLE, (tilt,)), "light")
    plain = fly_case(Case(NULL_INDEX, seed, aircraft, NULL), "light")
    found = {o.channel: o for o in trim_offsets([record], aircraft)[0]}["ax"]
    assert found.named and found.label == "ax bias or IMU pitch misalignment"
    assert found.entry == "misalignment" and abs(found.value - angle) <= found.bound
    null = {o.channel: o for o in trim_offsets([plain], aircraft)[0]}["ax"]
    assert not null.named and abs(null.value) < KINEMATIC_MATERIAL


def test_alpha_bias_named_as_its_class_within_its_bound():
    bias = Effect("bias", "longitudinal", "measured", {"channel": "alpha"}, {"value": 0.01})
    case = Case(0, 34, "navion", SINGLE, (bias,))
    scored = run_case(case, "light", truths(("navion",))["navion"], null=False, **FAST)
    assert scored.right is True
    found = scored.trim["longitudinal"]["alpha bias or CL_0 mismatch"]
    assert found.startswith("bias(alpha)")
    # the record, diagnosed: the longitudinal axis is no longer "no gap"
    result = diagnose([fly_case(case, "light")], "navion", **FAST)
    g = result.axes()["longitudinal"]
    named = [o for o in g.trim if o.named]
    assert [o.label for o in named] == ["alpha bias or CL_0 mismatch"]
    o = named[0]
    assert abs(o.value - 0.01) <= o.bound
    assert o.bound < 0.01  # the check resolves a 0.01 rad bias in light turbulence
    assert scored.magnitude_error <= o.bound / 0.01
    assert g.verdict != "no_gap"
    assert result.to_json()["axes"]["longitudinal"]["trim_named"][0].startswith(
        "alpha bias or CL_0 mismatch")


@pytest.mark.parametrize("aircraft", ["navion", "telemaster", "c172p"])
def test_tail_effectiveness_read_from_the_trim_elevator(aircraft):
    """A tail of effectiveness 0.8 trims at de_model / 0.8: the elevator offset is named as
    its class, and the factor that moves the model's trim elevator to the measured one,
    de_model / de_measured, is within its bound of 0.8 (the offset's Z sigma carried through
    k = m / x: Z sigma k / |x|; measured 0.767 +- 0.16, 0.795 +- 0.07, 0.800 +- 0.04)."""
    tail = Effect("control_effectiveness", "longitudinal", "card", {"surface": "de"},
                  {"factor": 0.8})
    offsets, _ = trim_offsets([fly_case(Case(0, 5, aircraft, SINGLE, (tail,)), "light")],
                              aircraft)
    o = next(o for o in offsets if o.channel == "de")
    assert o.named and o.label == "elevator bias, Cm_0 mismatch or tail effectiveness"
    k = o.tail_effectiveness
    assert k is not None and abs(k - 0.8) <= o.bound * k / abs(o.measured)
    assert "tail effectiveness factor" in o.text()


def test_rudder_bias_named_on_a_record_of_commands():
    bias = -math.radians(0.5)  # aerodynamic minus commanded deflection, rad
    case = Case(1, 35, "twinotter", SINGLE, (Effect(
        "actuator_bias", "lateral", "card", {"surface": "dr"}, {"bias": bias}),))
    record = fly_case(case, "light")
    # the flight core maps commands to positions statically: the recorded rudder is the
    # command; the record says so
    record.meta = replace(record.meta, extra={**record.meta.extra, SURFACES_KEY: "command"})
    result = diagnose([record], "twinotter", axis="lateral", **FAST)
    g = result.axes()["lateral"]
    named = {o.label: o for o in g.trim if o.named}
    assert "rudder bias or Cn_0 mismatch" in named
    o = named["rudder bias or Cn_0 mismatch"]
    assert o.entry == "actuator_bias" and o.channel == "dr"
    assert abs(o.value - bias) <= o.bound
    assert g.verdict != "no_gap"


def test_bound_is_z_sigma_and_value_in_catalogue_convention():
    record = fly_case(Case(NULL_INDEX, 36, "twinotter", NULL), "calm")
    offsets, _ = trim_offsets([record], "twinotter")
    for o in offsets:
        assert o.bound == pytest.approx((KINEMATIC_Z if o.kinematic else Z) * o.sigma)
        # a sensor bias and a misalignment are measured minus true, an actuator bias
        # aerodynamic minus measured
        assert o.value == pytest.approx(o.difference if o.entry in ("bias", "misalignment")
                                        else -o.difference)


def test_trim_classes_hold_what_the_trim_cannot_tell_apart():
    assert set(CHECKED_CLASSES) <= set(CLASSES)
    mass = Effect("mass_scale", "longitudinal", "card", {}, {"factor": 1.1})
    cg = Effect("cg_offset", "longitudinal", "card", {}, {"x": 0.05})
    rudder = Effect("actuator_bias", "lateral", "card", {"surface": "dr"}, {"bias": 0.01})
    assert classes_of(mass) == ["alpha bias or CL_0 mismatch"]
    assert classes_of(cg) == ["pitch stiffness",
                              "elevator bias, Cm_0 mismatch or tail effectiveness"]
    # a tail of effectiveness k trims the elevator at de_model / k (seed-13 rules)
    for tail in (Effect("control_effectiveness", "longitudinal", "card", {"surface": "de"},
                        {"factor": 0.85}),
                 Effect("tail_ice", "longitudinal", "card", {},
                        {"elevator": 0.85, "stability": 0.9, "damping": 0.9})):
        assert "elevator bias, Cm_0 mismatch or tail effectiveness" in classes_of(tail)
    assert classes_of(rudder) == ["rudder bias or Cn_0 mismatch"]
    # a deadband offsets a surface trimmed off zero by half its width (seed-10 rules)
    for surface, name in (("da", "aileron bias or Cl_0 mismatch"),
                          ("dr", "rudder bias or Cn_0 mismatch")):
        band = Effect("deadband", "lateral", "card", {"surface": surface}, {"width": 0.02})
        assert classes_of(band) == [name]


def test_beta_bias_named_on_the_span_after_the_lateral_maneuvers():
    """The card's lateral maneuvers start at 2 s, too soon to fix the sideslip's mean; the
    span from 8 s after the last one ends (34 s) to the record's end (64 s) does: a 0.86 deg
    vane bias is named as its class within its bound (Z sigma)."""
    bias = Effect("bias", "lateral", "measured", {"channel": "beta"}, {"value": 0.015})
    record = fly_case(Case(0, 37, "navion", SINGLE, (bias,)), "light")
    found = {o.channel: o for o in trim_offsets([record], "navion")[0]}["beta"]
    assert found.named and found.label == "beta bias or CY_0 / asymmetry"
    assert abs(found.value - 0.015) <= found.bound
    assert found.samples > 1000  # the late span's 22 s at 50 Hz, with the 2 s left out
