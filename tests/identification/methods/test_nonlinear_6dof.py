"""Output error on the nonlinear 6-DOF equations, scored against JSBSim truth.

Flights: the Navion at Teper's condition (sea level, 53.6 m/s) and the Twin Otter at
TM-4099's (1,897 m, 61.7 m/s), 50 Hz, an elevator 3211, an aileron doublet and a rudder
2-1-1 one after the other. Truth: ``sim.jsbsim.truth.derivatives`` in the axes of the model.

What limited the noise-free agreement (tests/identification/test_truth_recovery.py has the numbers):
JSBSim's default rectangular-Euler rate integrator (a half-step lag, now replaced by
Adams-Bashforth 2 in sim/jsbsim/model.py) and, for the Navion, lateral moments written about
the stability axes in its XML (``moment_axes="stability"``).
"""

from __future__ import annotations

import numpy as np
import pytest

from flightid.identification.estimate import StdKind
from flightid.identification.identify import identify
from flightid.identification.methods import nonlinear_6dof as n6
from flightid.identification.methods.nonlinear_6dof import simulation as sim6
from flightid.identification.methods.nonlinear_6dof.problem import cubic_midpoints
from flightid.identification.models import rigid_body as rb
from flightid.identification.models import six_dof
from flightid.scenarios.inputs import Doublet, ThreeTwoOneOne, TwoOneOne, total_signals
from flightid.sim.flight import simulation as flight
from flightid.sim.jsbsim import trim as trimming
from flightid.sim.jsbsim import truth
from flightid.units import DEG

RATE = 50.0
DURATION = 20.0


def _fly(aircraft: str, altitude: float, speed: float, amplitude_deg: float = 2.0,
         rudder: bool = True, axes: str = "body"):
    tr = trimming.trim(aircraft, altitude, speed)
    t = np.arange(0.0, DURATION + 0.5 / RATE, 1.0 / RATE)
    designs = [ThreeTwoOneOne(surface="de", start=1.0, base=0.4, amplitude=amplitude_deg * DEG),
               Doublet(surface="da", start=6.0, base=0.8, amplitude=2 * amplitude_deg * DEG)]
    if rudder:
        designs.append(TwoOneOne(surface="dr", start=11.0, base=0.6,
                                 amplitude=2 * amplitude_deg * DEG))
    record = flight.fly(aircraft, tr, total_signals(designs, t), duration_s=DURATION,
                        rate_hz=RATE)
    return record, truth.derivatives(aircraft, tr, axes=axes).values


@pytest.fixture(scope="module")
def navion():
    return _fly("navion", 0.0, 53.6448, axes="stability")


@pytest.fixture(scope="module")
def twin_otter():
    return _fly("twinotter", 1897.0, 61.733333)


def _navion_structure() -> dict[str, tuple[str, ...]]:
    # Lift and drag in stability axes, and the rolling and yawing moments too: the Navion's
    # XML writes them about the stability axes with stability-axis rates
    return six_dof.default_structure("stability", alphadot=True)


NAVION_OPTIONS = {"structure": _navion_structure(), "rotor_momentum": True,
                  "engine_torque": True, "moment_axes": "stability"}
NAVION_WELL_EXCITED = ("CL_alpha", "CL_de", "CD_alpha", "CY_beta", "CY_dr", "Cl_beta", "Cl_p",
                       "Cl_r", "Cl_da", "Cm_alpha", "Cm_q", "Cm_de", "Cm_alphadot", "Cn_beta",
                       "Cn_p", "Cn_r", "Cn_dr")


def _mean_inertia(record) -> rb.MassProperties:
    """Unit mass, the record's mean inertias and its local gravity."""
    inertia = (float(np.mean(record[c])) for c in ("Ixx", "Iyy", "Izz", "Ixz"))
    g = rb.local_gravity(float(record["latitude"][0]), float(record["h"][0]))
    return rb.MassProperties(1.0, *inertia, g=g)


def test_equations_of_motion_reproduce_jsbsim_accelerations(twin_otter):
    """The rigid-body equations with JSBSim's own forces give JSBSim's accelerations.

    Twin Otter (Ixz = 1430 kg m^2, so the roll-yaw coupling is exercised), during the
    elevator 3211 where the propellers add no yawing moment; record forces and moments
    are the aerodynamic ones plus thrust along x.
    """
    record, _ = twin_otter
    ref = record.meta.reference
    keep = record.time < 5.0
    x = np.array([record[s][keep] for s in rb.STATES])
    qs = record["qbar"][keep] * ref.area
    mass = record["mass"][keep]
    mp = _mean_inertia(record)
    udot, vdot, wdot = rb.translational(
        x, (qs * record["CX"][keep] + record["thrust"][keep]) / mass,
        qs * record["CY"][keep] / mass, qs * record["CZ"][keep] / mass, mp.g)
    pdot, qdot, rdot = rb.rotational(x, qs * ref.span * record["Cl"][keep],
                                     qs * ref.chord * record["Cm"][keep],
                                     qs * ref.span * record["Cn"][keep], mp)
    for name, model in (("pdot", pdot), ("qdot", qdot), ("rdot", rdot)):
        # 1e-4 rad/s^2: the order of the roll/yaw rates' coupling terms is 1e-6 here
        assert np.max(np.abs(model - record[name][keep])) < 1e-4, name
    # translational: integrate udot, wdot over the 5 s and compare with u, w (trapezoid
    # error and JSBSim's rotating earth, 0.01 m/s at most over 5 s)
    dt = record.dt
    for name, rate in (("u", udot), ("w", wdot)):
        integral = record[name][0] + np.concatenate(
            [[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1])) * dt])
        assert np.max(np.abs(integral - record[name][keep])) < 0.02, name


def test_local_gravity_is_wgs84_normal_gravity():
    assert rb.local_gravity(0.0) == pytest.approx(9.7803253359, abs=1e-9)
    assert rb.local_gravity(np.pi / 2) == pytest.approx(9.8321849378, abs=1e-8)
    assert rb.local_gravity(0.0, 1000.0) == pytest.approx(9.7803253359 - 3.087e-3, abs=2e-6)


def test_complex_step_sensitivities_match_central_differences(navion):
    record, _ = navion
    short = record.slice(0.0, 4.0)
    model = n6.model_from_record(short, six_dof.default_structure("stability", alphadot=True),
                                 rotor_momentum=True)
    problem = n6.problem_from_record(short, model, initial_state="estimate")
    values = {**model.start, "x0_q": 0.01, "h_engine": -500.0}
    names = ["CL_alpha", "Cm_q", "Cm_alphadot", "h_engine", "x0_q", "Cl_p"]
    _, sens = sim6.outputs_and_sensitivities(problem, values, names)
    for k, name in enumerate(names):
        h = 1e-5 * max(1.0, abs(values[name]))
        up = sim6.outputs(problem, {**values, name: values[name] + h})
        down = sim6.outputs(problem, {**values, name: values[name] - h})
        fd = (up - down) / (2 * h)
        scale = np.max(np.abs(fd)) + 1e-12
        # central differences are accurate to O(h^2) ~ 1e-8 relative here
        assert np.max(np.abs(sens[:, :, k] - fd)) < 1e-5 * scale, name


def test_navion_noise_free_derivatives_within_two_percent(navion):
    record, true = navion
    est = identify(record, "oe6dof", "6dof_stability", initial_state="measured",
                   colored=False, **NAVION_OPTIONS)
    assert est.fit["converged"], est.fit["reason"]
    assert est.unidentifiable == {}
    errors = {n: (est[n] - true[n]) / true[n] for n in NAVION_WELL_EXCITED}
    # measured: largest |error| 0.89 % (Cn_r), all others below 0.4 %
    for name, error in errors.items():
        assert abs(error) < 0.02, f"{name}: {100 * error:.2f} %"
    # the propeller: JSBSim's gyroscopic moment and torque (measured from the moment
    # budget of the record: 524 N m s and -421 N m)
    assert est["h_engine"] == pytest.approx(-524.4, rel=0.01)
    assert est["L_engine"] == pytest.approx(-421.5, rel=0.02)


def test_twin_otter_noise_free_derivatives(twin_otter):
    record, true = twin_otter
    # the engine model's propulsive moments as inputs: the propellers' differential thrust
    # in r and beta is not aerodynamic (without them Cn_r +2.1 %, Cn_p -1.6 %)
    model = n6.model_from_record(record, force_axes="body", propulsive_moments=True)
    est = n6.estimate(record, model)
    assert est.fit["converged"], est.fit["reason"]
    # measured: largest |error| 0.39 % (Cm_q, CZ_de), all lateral ones below 0.13 %; CZ_q
    # and the tiny Cn_da are not well excited by these inputs and are not checked
    well_excited = ("CX_alpha", "CZ_alpha", "CZ_de", "Cm_alpha", "Cm_q", "Cm_de", "CY_beta",
                    "CY_r", "CY_dr", "Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr", "Cn_beta",
                    "Cn_p", "Cn_r", "Cn_dr")
    for name in well_excited:
        assert est[name] == pytest.approx(true[name], rel=0.01), name
    # the fitted model predicts the record it was fitted to (simulate = the fit's model)
    values = {n: est[n] for n in est.names}
    predicted = sim6.simulate(record, model, values)
    for name in ("q", "r", "az"):
        np.testing.assert_allclose(predicted[name], est.outputs[name]["model"], atol=1e-12)


@pytest.mark.parametrize("seed", [3, 7])
def test_navion_with_noise_within_three_cramer_rao_bounds(navion, seed):
    """White noise on every output: the errors are within 3 Cramer-Rao standard errors.

    Noise (1 sigma): V 0.5 m/s, angles 0.5 deg, rates 1 deg/s, accelerations 0.1 m/s^2,
    the class of a low-cost air-data and MEMS suite; the bounds are then 1.2-11 % of the
    derivatives, so the model error of the noise-free fit (at most 1.8 %, Cn_r, i.e. 1.2
    bounds) stays inside them. The initial state is estimated (a noisy first sample would
    bias it). Plain Cramer-Rao bounds: the residuals are the white noise plus that small
    model error, and the colored-residual correction (M&K eq. 6.54) is not needed; from
    output-error residuals, which are orthogonal to the sensitivities at the optimum, it
    comes out 10-40 % smaller than the plain bound here, so it would only make the test
    harder. Measured: largest |z| 2.5 (seed 3, Cl_da), 2.0 (seed 7, Cm_alpha); seeds 5 and
    11 give 1.7 and 2.9.
    """
    record, true = navion
    sigma = {"V": 0.5, "alpha": 0.5 * DEG, "beta": 0.5 * DEG, "p": 1.0 * DEG,
             "q": 1.0 * DEG, "r": 1.0 * DEG, "phi": 0.5 * DEG, "theta": 0.5 * DEG,
             "psi": 0.5 * DEG, "ax": 0.1, "ay": 0.1, "az": 0.1}
    rng = np.random.default_rng(seed)
    noisy = record.with_channels(**{c: record[c] + s * rng.standard_normal(len(record))
                                    for c, s in sigma.items()})
    model = n6.model_from_record(noisy, _navion_structure(), rotor_momentum=True,
                                 engine_torque=True)
    est = n6.estimate(noisy, model, initial_state="estimate")
    assert est.fit["converged"], est.fit["reason"]
    assert est.std_kind == StdKind.CRAMER_RAO
    for name in NAVION_WELL_EXCITED:
        z = (est[name] - true[name]) / est.std_of(name)
        assert abs(z) < 3.0, f"{name}: {est[name]:.5g} vs {true[name]:.5g}, z = {z:.2f}"
    # R re-estimated every iteration recovers the injected noise (1001 samples: the
    # sample standard deviation scatters by 2.2 %)
    for name in ("V", "q", "az", "beta"):
        assert est.fit["noise_std"][name] == pytest.approx(sigma[name], rel=0.07)


def test_rudder_derivatives_unidentifiable_without_rudder_input():
    record, _ = _fly("navion", 0.0, 53.6448, rudder=False)
    record = record.slice(0.0, 10.0)
    model = n6.model_from_record(record, six_dof.default_structure("stability"))
    est = n6.estimate(record, model, max_iterations=3)
    assert set(est.unidentifiable) == {"CY_dr", "Cl_dr", "Cn_dr"}
    assert all("input dr is not excited" in why for why in est.unidentifiable.values())


def test_propulsive_moments_close_the_twin_otter_moment_budget(twin_otter):
    """JSBSim's rates change = aerodynamic + recorded propulsive moments (N m), to rounding.

    Over the whole flight, rudder and aileron included: the propellers' differential
    thrust is in N_prop, which a model without it would read as aerodynamics.
    """
    record, _ = twin_otter
    ref = record.meta.reference
    x = np.array([record[s] for s in rb.STATES])
    qs = record["qbar"] * ref.area
    mp = _mean_inertia(record)
    aero = (qs * ref.span * record["Cl"], qs * ref.chord * record["Cm"],
            qs * ref.span * record["Cn"])
    total = [a + record[c] for a, c in zip(aero, six_dof.PROPULSIVE_MOMENTS, strict=True)]
    rdot_aero = rb.rotational(x, *aero, mp)[2]
    rdot_total = rb.rotational(x, *total, mp)[2]
    assert np.std(record["N_prop"]) > 10.0  # N m: the differential thrust is there
    assert np.max(np.abs(rdot_total - record["rdot"])) < 1e-4
    assert np.max(np.abs(rdot_aero - record["rdot"])) > 1e-3


def test_cubic_midpoints_exact_for_cubics():
    t = np.linspace(0.0, 1.0, 11)
    x = np.column_stack([1 + 2 * t - 3 * t**2 + 4 * t**3, np.sin(t)])
    mid = cubic_midpoints(x)
    tm = 0.5 * (t[1:] + t[:-1])
    exact = 1 + 2 * tm - 3 * tm**2 + 4 * tm**3
    assert np.allclose(mid[1:-1, 0], exact[1:-1], atol=1e-12)
    # the end intervals fall back to the linear mean
    assert mid[0, 0] == pytest.approx(0.5 * (x[0, 0] + x[1, 0]))


def test_bad_inputs_are_named(navion):
    record, _ = navion
    no_thrust = record.with_channels()
    del no_thrust.channels["thrust"]
    model = n6.model_from_record(record)
    with pytest.raises(ValueError, match="thrust"):
        n6.problem_from_record(no_thrust, model)
    no_moments = record.with_channels()
    del no_moments.channels["N_prop"]
    with pytest.raises(ValueError, match="N_prop"):
        n6.problem_from_record(no_moments, n6.model_from_record(record, propulsive_moments=True))
    with pytest.raises(ValueError, match="controls must be one of linear, cubic, zoh"):
        n6.problem_from_record(record, model, controls="spline")
    with pytest.raises(ValueError, match="alphadot is allowed in moment coefficients only"):
        n6.model_from_record(record, {"CL": ("alpha", "alphadot")})
    with pytest.raises(ValueError, match="belongs to force_axes='stability'"):
        n6.model_from_record(record, {"CL": ("alpha",)}, force_axes="body")
    with pytest.raises(ValueError, match="6dof or 6dof_stability"):
        n6.run(record, "6dof_wind")


def test_equation_error_start_keeps_the_fixed_parameters(navion):
    # a parameter left out of ``free`` is held at its a priori value; the equation-error
    # start once overwrote it (on the Telemaster card that held CL_q at a noisy regression
    # value and scattered CL_de 4.6 bounds)
    record, true = navion
    a_priori = 1.5 * true["Cm_alphadot"]
    model = n6.model_from_record(record, _navion_structure(), rotor_momentum=True,
                                 engine_torque=True, moment_axes="stability",
                                 start={"Cm_alphadot": a_priori})
    free = [p for p in model.parameters if p != "Cm_alphadot"]
    est = n6.estimate(record, model, free=free, start="equation_error", max_iterations=1)
    assert est.fit["fixed"]["Cm_alphadot"] == a_priori
    assert "Cm_alphadot" not in est.names
