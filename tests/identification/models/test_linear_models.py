"""Linear model structures: matrices from derivatives, sign conventions, sensitivities."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.models import linear as lm
from flightid.identification.models.discrete import simulate
from flightid.identification.models.reference_condition import (
    ReferenceCondition,
    condition_from_record,
)
from flightid.record import FlightRecord, RecordMeta, Reference
from flightid.units import FT, SLUG, SLUG_FT2

# Twin Otter, record totter_f1_017 (Morelli & Klein 2016, example 6.1)
COND = ReferenceCondition(
    V=237.02 * FT, qbar=2696.6, alpha=0.0040, theta=0.0286, mass=339.30 * SLUG,
    Ixx=20902 * SLUG_FT2, Iyy=24256 * SLUG_FT2, Izz=38463 * SLUG_FT2, Ixz=1127 * SLUG_FT2,
    area=422.48 * FT**2, span=64.99 * FT, chord=6.496 * FT,
)
PUBLISHED = {
    "CY_beta": -0.8646, "CY_r": 0.9331, "CY_dr": 0.3800, "Cl_beta": -0.11959,
    "Cl_p": -0.5859, "Cl_r": 0.1889, "Cl_da": -0.2282, "Cl_dr": 0.0422, "Cn_beta": 0.08638,
    "Cn_p": -0.06441, "Cn_r": -0.19059, "Cn_da": -0.00298, "Cn_dr": -0.13548,
}


def test_lateral_matrix_entries_follow_the_equations():
    model = lm.lateral(COND, start=PUBLISHED)
    A, B, C, D = model.matrices()
    c = COND
    gamma = c.Ixx * c.Izz - c.Ixz**2
    qsb = c.qbar * c.area * c.span
    b2v = c.span / (2 * c.V)
    # roll damping with inertia coupling (M&K eq. 3.37): (Izz Cl_p + Ixz Cn_p) qSb b/2V / Gamma
    lp = qsb * b2v * (c.Izz * PUBLISHED["Cl_p"] + c.Ixz * PUBLISHED["Cn_p"]) / gamma
    assert A[1, 1] == pytest.approx(lp, rel=1e-12)
    nb = qsb * (c.Ixz * PUBLISHED["Cl_beta"] + c.Ixx * PUBLISHED["Cn_beta"]) / gamma
    assert A[2, 0] == pytest.approx(nb, rel=1e-12)
    assert A[0, 2] == pytest.approx(PUBLISHED["CY_r"] * b2v * c.qbar * c.area / (c.mass * c.V)
                                    - np.cos(c.alpha), rel=1e-12)
    assert A[0, 3] == pytest.approx(c.g * np.cos(c.theta) / c.V, rel=1e-12)
    assert A[3].tolist() == [0.0, 1.0, pytest.approx(np.tan(c.theta)), 0.0]
    # ay = qbar S CY / m: the beta entry of C and the rudder entry of D
    assert C[4, 0] == pytest.approx(c.qbar * c.area * PUBLISHED["CY_beta"] / c.mass)
    assert D[4, 1] == pytest.approx(c.qbar * c.area * PUBLISHED["CY_dr"] / c.mass)
    assert B.shape == (4, 3) and D.shape == (5, 3)  # da, dr and the bias column


def test_twin_otter_modes_are_those_of_a_light_twin():
    A = lm.lateral(COND, start=PUBLISHED).matrices()[0]
    eig = np.linalg.eigvals(A)
    complex_pair = eig[np.abs(eig.imag) > 1e-6]
    real = np.sort(eig[np.abs(eig.imag) <= 1e-6].real)
    wn = np.abs(complex_pair[0])
    zeta = -complex_pair[0].real / wn
    # Dutch roll about 1.5 rad/s lightly damped; roll subsidence near the roll damping
    # Lp = qbar S b^2 Cl_p / (2 V Ixx) (single-degree approximation, within 15 %)
    lp = COND.qbar * COND.area * COND.span**2 * PUBLISHED["Cl_p"] / (2 * COND.V * COND.Ixx)
    assert 1.0 < wn < 2.5 and 0.05 < zeta < 0.4
    assert real[0] == pytest.approx(lp, rel=0.15)
    assert abs(real[1]) < 0.1  # spiral: slow


def test_control_signs_follow_the_project_convention():
    t = np.arange(0.0, 0.5, 0.02)
    model = lm.lateral(COND, start=PUBLISHED)
    y = simulate(model, model.start, t, np.column_stack([np.full(t.size, 0.05), 0 * t]))
    assert y[-1, 1] < 0  # da > 0 (right aileron TE down) rolls left: p < 0
    y = simulate(model, model.start, t, np.column_stack([0 * t, np.full(t.size, 0.05)]))
    assert y[5, 2] < 0  # dr > 0 (TE left) yaws nose left: r < 0
    sp = lm.short_period(COND, start={"Cm_de": -1.2, "CL_de": 0.4, "Cm_alpha": -1.0,
                                      "Cm_q": -20.0, "CL_alpha": 5.5})
    y = simulate(sp, sp.start, t, np.full((t.size, 1), 0.05))
    assert y[5, 1] < 0  # de > 0 (TE down) pitches nose down: q < 0


def test_complex_step_sensitivities_equal_finite_differences_with_alphadot():
    model = lm.short_period(COND, derivatives=lm.SHORT_PERIOD_DERIVATIVES,
                            start={"Cm_alphadot": -6.0, "CL_q": 4.0, "bias_alphadot": 0.01})
    values = model.values()
    names = list(model.parameters)
    _, grads = lm.matrix_sensitivities(model, values, names)
    for k, name in enumerate(names):
        h = 1e-6
        up = model.matrices({**values, name: values[name] + h})
        down = model.matrices({**values, name: values[name] - h})
        for slot in range(4):
            fd = (up[slot] - down[slot]) / (2 * h)
            np.testing.assert_allclose(grads[slot][k], fd, rtol=1e-6, atol=1e-8 * (
                1 + np.abs(fd).max()), err_msg=f"{name} matrix {'ABCD'[slot]}")


def test_full_longitudinal_has_a_phugoid_and_a_short_period():
    c = ReferenceCondition(V=53.6, qbar=1760.0, alpha=0.0, theta=0.0, mass=1247.0,
                           Ixx=1420.0, Iyy=4067.0, Izz=4786.0, Ixz=0.0, area=17.1,
                           span=10.2, chord=1.74)
    model = lm.longitudinal(c, derivatives=lm.LONGITUDINAL_DEFAULT + ("Cm_alphadot",),
                            start={"CD_0": 0.05, "CD_alpha": 0.33, "CL_alpha": 4.44,
                                   "CL_de": 0.355, "Cm_alpha": -0.683, "Cm_q": -9.96,
                                   "Cm_de": -0.923, "Cm_alphadot": -4.36})
    eig = np.linalg.eigvals(model.matrices()[0])
    wn = np.sort(np.abs(eig))
    # Navion (Nelson 1998, example 4.2): phugoid about 0.2 rad/s, short period about 3.6
    assert 0.1 < wn[0] < 0.4 and 2.5 < wn[-1] < 5.0
    # CL_0 starts at the weight balance m g / (qbar S)
    assert model.start["CL_0"] == pytest.approx(c.mass * c.g / (c.qbar * c.area))


def test_bad_names_and_conditions_are_reported():
    with pytest.raises(ValueError, match="no parameter Cm_q"):
        lm.lateral(COND, derivatives=("Cl_p", "Cm_q"))
    with pytest.raises(ValueError, match="start value for Cl_zz"):
        lm.lateral(COND, start={"Cl_zz": 1.0})
    with pytest.raises(KeyError, match="no parameter Cn_q"):
        lm.lateral(COND).values(Cn_q=1.0)
    with pytest.raises(ValueError, match="mass must be positive"):
        ReferenceCondition(**{**COND.__dict__, "mass": -1.0})
    with pytest.raises(ValueError, match="thrust must be finite"):
        ReferenceCondition(**{**COND.__dict__, "thrust": float("nan")})
    t = np.arange(10) * 0.02
    rec = FlightRecord(t, {"V": 50 + 0 * t}, RecordMeta(reference=Reference(10.0, 5.0, 1.0)))
    with pytest.raises(ValueError, match="no channel 'qbar'.*qbar="):
        condition_from_record(rec)
    cond = condition_from_record(rec, qbar=1500.0, alpha=0.0, theta=0.0, mass=1000.0,
                                    Ixx=1.0, Iyy=1.0, Izz=1.0, Ixz=0.0)
    assert cond.V == 50.0 and cond.span == 5.0


def test_longitudinal_trim_balance_and_thrust_input():
    # Telemaster-like: 15 m/s, alpha 4.8 deg, thrust 14.8 N, climbing 2 deg
    c = ReferenceCondition(V=15.0, qbar=137.5, alpha=0.084, theta=0.119, mass=11.0,
                           Ixx=1.0, Iyy=1.2, Izz=2.0, Ixz=0.0, area=0.83, span=2.26,
                           chord=0.35, thrust=14.8)
    weight, qs, gamma = c.mass * c.g, c.qbar * c.area, c.theta - c.alpha
    plain = lm.longitudinal(c, derivatives=lm.LONGITUDINAL_DERIVATIVES)
    # lift and drag balance weight and thrust in stability axes (thrust along body x)
    assert plain.start["CL_0"] == pytest.approx(
        (weight * np.cos(gamma) - c.thrust * np.sin(c.alpha)) / qs)
    assert plain.start["CD_0"] == pytest.approx(
        (c.thrust * np.cos(c.alpha) - weight * np.sin(gamma)) / qs)
    values = {**plain.start, "Cm_alphadot": -4.0, "CL_de": 0.36, "Cm_de": -0.94,
              "bias_qdot": 0.01}
    powered = lm.longitudinal(c, derivatives=lm.LONGITUDINAL_DERIVATIVES, thrust_input=True)
    assert powered.inputs == ("de", "thrust")
    A0, B0, C0, D0 = plain.build(values)
    A, B, C, D = powered.build(values)
    # the elevator and bias columns are those of the model without the thrust input
    np.testing.assert_allclose(A, A0)
    np.testing.assert_allclose(B[:, [0, 2]], B0)
    np.testing.assert_allclose(D[:, [0, 2]], D0)
    # a thrust change dT (N) accelerates along body x: dT cos(alpha)/m in Vdot,
    # -dT sin(alpha)/(m V) in alphadot, the latter's Cm_alphadot moment in qdot
    mad = -4.0 * c.chord / (2 * c.V)
    k_m = c.qbar * c.area * c.chord / c.Iyy
    alphadot = -np.sin(c.alpha) / (c.mass * c.V)
    np.testing.assert_allclose(
        B[:, 1], [np.cos(c.alpha) / c.mass, alphadot, k_m * mad * alphadot, 0.0])
    assert np.all(D[:, 1] == 0.0)  # body-x force: no az


def test_reference_condition_is_the_trim_before_the_first_maneuver():
    # a record whose speed runs away after its maneuver starts (2 s): the model is
    # linearised about the trim before it, not about the record's mean
    t = np.arange(0, 10, 0.02)
    speed = np.where(t < 2.0, 50.0, 50.0 + (t - 2.0))
    chans = {"V": speed, "qbar": 0.6 * speed**2, "alpha": 0.05 + 0 * t,
             "theta": 0.05 + 0 * t, "mass": 1000 + 0 * t, "Ixx": 1 + 0 * t,
             "Iyy": 1 + 0 * t, "Izz": 1 + 0 * t, "Ixz": 0 * t}
    maneuvers = [{"kind": "doublet", "surfaces": ["de"], "start": 2.0, "end": 3.0}]
    listed = FlightRecord(t, chans, RecordMeta(reference=Reference(10.0, 5.0, 1.0),
                                                extra={"maneuvers": maneuvers}))
    cond = lm.condition_from_record(listed)
    assert cond.V == pytest.approx(50.0) and cond.qbar == pytest.approx(1500.0)
    unlisted = FlightRecord(t, chans, RecordMeta(reference=Reference(10.0, 5.0, 1.0)))
    assert lm.condition_from_record(unlisted).V == pytest.approx(np.mean(speed))
    # less than MIN_TRIM_S of trim before the maneuver: the mean again
    late = [{**maneuvers[0], "start": 0.3}]
    short = FlightRecord(t, chans, RecordMeta(reference=Reference(10.0, 5.0, 1.0),
                                               extra={"maneuvers": late}))
    assert lm.condition_from_record(short).V == pytest.approx(np.mean(speed))
