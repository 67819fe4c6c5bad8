"""Card-noise truth recovery for the Twin Otter and the Telemaster (issue 5, second done-when).

Each aircraft's identification card (``scenarios/library/<aircraft>-id.toml``) is flown
in JSBSim on two fixed seeds, the measured record is processed as a flight-test engineer
would, identified by output error (initial states estimated, colored-residual bounds, M&K
2016 eq. 6.54) and scored against the JSBSim aerodynamic truth
``sim.jsbsim.truth.derivatives(..., axes="body")`` at the card's trim:
- Twin Otter: the nonlinear 6-DOF model on the whole record, body axes, with the engine
  model's thrust and propulsive moments (L_prop, M_prop, N_prop) as inputs. The two
  propellers at y = +-2.78 m make a differential thrust in yaw rate and sideslip
  (N_prop = -1357 N m s/rad r - 1086 N m/rad beta on this card); linear perturbation
  models without it read it as aerodynamics (Cn_r between the aerodynamic and the
  frozen-rpm total truth, Cl_dr +4 %, CY_r +1.4 % before).
- Telemaster: the full longitudinal model (V, alpha, q, az; the measured thrust as a
  second input; CL_q and Cm_alphadot a priori as in the demo, CL_0 and CD_0 at the trim
  force balance) and the full lateral model; the hobby suite has no attitudes for the
  6-DOF model. The short period holds the speed, which at 15 m/s and CL_0 0.93 misreads
  the doublet (noise-free CL_de -39 %, 20 seeds CL_de z mean -1.6).

Processing:
- Twin Otter, research suite: accelerometers moved to the CG with the IMU position of the
  installation (M&K 2016 eq. 10.9, gyros differentiated), then flight path reconstruction
  (``compatibility.reconstruct``, vane positions known from the drawings, M&K ch. 10)
  estimates the inertial biases and the vane flow amplifications and corrects the record.
  The GPS latitude gives both the local gravity (with G0 instead of the 9.775 m/s^2 of
  the flight, the roll derivatives came out 1 % low).
- Telemaster, hobby suite: no attitude channels, so no reconstruction. The 100 Hz IMU is
  low-passed zero-phase at 8 Hz (the engine lines alias to about 20 and 40 Hz, there is no
  anti-alias filter) and the record is taken at the 25 Hz DAS sample instants, where the
  vane, surface and airspeed samples are exact (no hold delay). Accelerometers are moved
  to the CG as above; the boom vanes are corrected with the thesis's calibration (Sofyan,
  App. 2: 1 m ahead of the CG, K = 0.0136) by ``compatibility.correct``. The lateral model
  has no phi output (none measured); the pitch attitude of the reference condition comes
  from the trimmed specific force, theta0 = atan2(ax, -az) (level flight). The surface
  potentiometers (0.2/0.3 deg noise, 0.25 deg steps, on a 2 deg aileron pulse, a 1.5 deg
  rudder and a 3 deg elevator doublet) are errors in the variables (output error takes
  its inputs as exact: the raw noise shrank Cl_beta, Cl_p, Cl_da by 13 % and doubled the
  Cm_alpha scatter): the aileron and rudder are estimated as multisteps, levels and
  sub-sample edge times with the derivatives (``output_error.estimate(...,
  multistep_inputs=...)``), the elevator is made piecewise constant
  (``input_denoising.piecewise_constant``); see KNOWN for why each.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.signal

from flightid.identification.compatibility import reconstruction as compat
from flightid.identification.data import input_denoising, windows
from flightid.identification.methods import nonlinear_6dof as n6
from flightid.identification.methods import output_error
from flightid.identification.models import linear as lm
from flightid.identification.models import six_dof
from flightid.identification.models.reference_condition import condition_from_record
from flightid.record import FlightRecord
from flightid.scenarios.cards import fly_card, load_card
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.jsbsim.truth import derivatives

IMU = ("p", "q", "r", "ax", "ay", "az")
DAS_RATE = 25.0  # Hz, Sofyan (RMIT thesis, c. 1997) ch. 6
IMU_CUTOFF = 8.0  # Hz: below the DAS Nyquist (12.5 Hz), above the aircraft modes (< 2 Hz)
# hobby suite, servo-pot surfaces (errors in variables, see KNOWN): the elevator made
# piecewise constant, the aileron and rudder estimated as multisteps by output error
DENOISED_SURFACES = ("de",)
MULTISTEP_INPUTS = ("da", "dr")
WELL_EXCITED = ("Cm_alpha", "Cm_de", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr")
# relative tolerance for the well-excited derivatives: research, 6-DOF: 1 %, 3 times the
# largest corrected bound among them (Cl_p 0.21 %) rounded up, measured worst 0.32 %
# (Cl_p seed 1); hobby: about 3 times the corrected bounds (5-10 %)
RELATIVE = {"twinotter": 0.01, "telemaster": 0.35}
# the Telemaster's body-axis Cn_beta is -0.0016 (its XML writes Cn in stability axes, at
# 10 deg trim alpha the body value is nearly cancelled by Cl_beta sin alpha): a relative
# tolerance is meaningless there, the 3-sigma test still applies
NO_RELATIVE = {("telemaster", "Cn_beta")}


def _mounting(card, name: str):
    return next(m for m in card.sensors.mounting if m.name == name)


def cg_accelerations(record: FlightRecord, x: float, y: float, z: float) -> FlightRecord:
    """Accelerometers at (x, y, z) m from the CG (body axes) moved to the CG (m/s^2).

    a_cg = a_sensor - omega_dot x r - omega x (omega x r) (M&K 2016 eq. 10.9), with the
    angular accelerations differentiated from the measured rates.
    """
    t = record.time
    p, q, r = record["p"], record["q"], record["r"]
    pd, qd, rd = (np.gradient(record[c], t) for c in ("p", "q", "r"))
    c1, c2, c3 = q * z - r * y, r * x - p * z, p * y - q * x  # omega x r
    return record.with_channels(
        ax=record["ax"] - (qd * z - rd * y) - (q * c3 - r * c2),
        ay=record["ay"] - (rd * x - pd * z) - (r * c1 - p * c3),
        az=record["az"] - (pd * y - qd * x) - (p * c2 - q * c1))


def at_das_instants(record: FlightRecord) -> FlightRecord:
    """The hobby record at the 25 Hz DAS sample instants, IMU low-passed zero-phase first."""
    fs = record.meta.sample_rate
    b, a = scipy.signal.butter(4, IMU_CUTOFF / (fs / 2))
    step = int(round(fs / DAS_RATE))
    channels = {c: (scipy.signal.filtfilt(b, a, x) if c in IMU else x)[::step]
                for c, x in record.channels.items()}
    meta = dataclasses.replace(record.meta, sample_rate=DAS_RATE)
    return FlightRecord(record.time[::step], channels, meta)


def process(card, measured: FlightRecord) -> FlightRecord:
    """The measured record made ready for output error (see the module docstring)."""
    arm, vanes = _mounting(card, "lever_arm"), _mounting(card, "vanes")
    if card.sensors.name == "research":
        record = cg_accelerations(measured, arm.x, arm.y, arm.z)
        corrected, est = compat.reconstruct(
            record, fixed={"vane_alpha_x": vanes.alpha_x, "vane_beta_x": vanes.beta_x})
        assert est.fit["converged"], est.fit["reason"]
        return corrected
    record = cg_accelerations(at_das_instants(measured), arm.x, arm.y, arm.z)
    record = input_denoising.denoise_channels(record, DENOISED_SURFACES)
    return compat.correct(record, {"vane_alpha_x": vanes.alpha_x, "vane_beta_x": vanes.beta_x,
                                   "upwash_alpha": vanes.upwash,
                                   "sidewash_beta": vanes.sidewash})


# full longitudinal model of the hobby card: CL_q and Cm_alphadot a priori (as the demo),
# CL_0 and CD_0 at the trim force balance (linear_models.longitudinal)
LONGITUDINAL = ("CL_0", "CL_alpha", "CL_q", "CL_de", "CD_0", "CD_alpha",
                "Cm_alpha", "Cm_q", "Cm_de", "Cm_alphadot")
TRIM_BALANCE = ("CL_0", "CD_0")
# held at their truth values: this test isolates the noise of the hobby sensors
A_PRIORI = ("CL_q", "Cm_alphadot")


def identify(card, record: FlightRecord, truth: dict[str, float], settle: float):
    """Full longitudinal and lateral output error on the card's windows."""
    override = {}
    if "theta" not in record:
        pre = record.slice(0.0, min(m.start for m in card.maneuvers) - 0.1)
        override["theta"] = float(np.arctan2(np.mean(pre["ax"]), -np.mean(pre["az"])))
    t0, t1 = windows.window(record, ("de",))
    t1 = min(t1, max(m.end for m in card.maneuvers if "de" in m.surfaces()) + settle)
    lon = record.slice(t0, t1)
    model = lm.longitudinal(condition_from_record(lon, **override), derivatives=LONGITUDINAL,
                            start={n: truth[n] for n in A_PRIORI},
                            thrust_input="thrust" in lon)
    if "theta" not in lon:
        model = lm.without_outputs(model, ("theta",))
    free = [p for p in model.parameters if p not in (*A_PRIORI, *TRIM_BALANCE)]
    lo = output_error.estimate(lon, model, free=free, start="equation_error",
                               initial_state="estimate", colored=True)
    t0, t1 = windows.window(record, ("da", "dr"))
    lat = record.slice(t0, t1)
    model = lm.lateral(condition_from_record(lat, **override),
                       derivatives=lm.LATERAL_DERIVATIVES)
    if "phi" not in lat:
        model = lm.without_outputs(model, ("phi",))
    la = output_error.estimate(lat, model, start="equation_error", initial_state="estimate",
                               colored=True, multistep_inputs=MULTISTEP_INPUTS)
    return [lo, la]


def identify_6dof(record: FlightRecord):
    """6-DOF output error on the whole record, the propulsion's forces and moments as inputs."""
    model = n6.model_from_record(record, six_dof.default_structure("body"), propulsive_moments=True)
    return [n6.estimate(record, model, initial_state="estimate", colored=True)]


CASES = [("twinotter-id", 1), ("twinotter-id", 2), ("telemaster-id", 1), ("telemaster-id", 2)]


@pytest.fixture(scope="module", params=CASES, ids=[f"{c}-seed{s}" for c, s in CASES])
def flight(request):
    name, seed = request.param
    card = load_card(name)
    measured, _ = fly_card(card, seed)
    c = card.condition
    model = load(card.aircraft)
    trimmed = trim(model, c.altitude_m, c.speed_m_s, c.gamma_rad, c.bank_rad, c.flaps_rad)
    truth = derivatives(model, trimmed, axes="body").values
    record = process(card, measured)
    if card.sensors.name == "research":
        estimates = identify_6dof(record)
    else:
        estimates = identify(card, record, truth, windows.SETTLE_S)
    rows = {n: (e[n], e.std_of(n), truth[n]) for e in estimates for n in e.names
            if n in truth and not n.endswith("_0") and n not in e.unidentifiable}
    return card, seed, estimates, rows, truth


# Measured exceptions (seed, derivative): sigmas, with the cause where it is known.
# Twin Otter: none. Two causes of 0.1-1 % offsets that repeated on every noise seed were
# found and removed (16-seed Monte Carlo of the card, research noise, 6-DOF fit):
# - JSBSim's rectangular-Euler attitude integrator (Euler angles 1.25 ms behind the
#   rates): Cl_beta, Cl_p, Cl_da -0.53 to -0.60 %, CY_beta -0.28 % -> -0.02 to -0.05 %
#   with Adams-Bashforth 2 (sim/jsbsim/model.py);
# - the thrust and propulsive moments copied past the 10 Hz anti-alias filters (0.04 s
#   ahead of every other channel): Cn_beta, Cn_r, Cn_dr +0.10 to +0.20 % -> +0.01 to
#   +0.03 % through the same filter (sim/sensors/builtin.py research_suite).
# What is left: the corrected bounds are 0.6-1.0 of the Monte Carlo scatter (Cl_p 0.92,
# Cn_r 0.62, Cm_alpha 0.66, Cl_r 0.44), and CZ_q +1.3 % (+-0.4 %, bound 1.0 %).
# Telemaster (hobby suite, linear models): no exception on the two seeds. Over seeds 1-20
# (same truth flight), 3 have a derivative beyond 3 sigma, all longitudinal: 10
# (CD_alpha +3.7), 18 (Cm_alpha -4.2), 19 (Cm_de -3.4). Measured by taking effects out of
# the suite and by changing the processing (10-20 noise seeds each):
# - lateral, solved: the measured surfaces are errors in the variables. Output error
#   takes its inputs as exact; the servo-pot noise (0.2-0.3 deg, Sofyan Table 8-6, on
#   a 2 deg aileron pulse and a 1.5 deg rudder doublet) shrank Cl_beta, Cl_p, Cl_da by
#   13 %; made piecewise constant (input_denoising) they read +6.4/+5.9/+8.0 %, and the
#   25 Hz sampling was left: the roll derivatives move by about 1.4 % per ms of input
#   timing, and a step between two 40 ms samples lands on the grid (noise-free, the
#   exact 25 Hz surface samples interpolated read Cl_da +9.6 %; at 100 Hz +1.7 %). With
#   the aileron and rudder estimated as multisteps (MULTISTEP_INPUTS, multistep_input:
#   levels and sub-sample edge times with the derivatives, the surfaces as outputs), 20
#   seeds: lateral z sd 0.84-1.35 (was 0.95-1.35), z mean -0.9 to +0.3, no lateral
#   derivative beyond 3 sigma (was 4 seeds: 1 Cl_dr +3.07, 14 Cn_da +3.1, 17 Cl_beta
#   -3.4, 19 Cn_dr -4.0); the bounds grew with the timing they now carry (Cl_da 5.7 ->
#   7.8 %). Tried and not kept: filter error with process noise on p, r (Cl -35 %);
#   filter error with the surface noise as known process noise through B (Cl -24 %, the
#   errors-in-variables trap: conditioned on the measured input its noise is not
#   independent of it); linear smoothers (Cl_da +15 %); the surface samples near the
#   edges left out of the multistep fit (the edges then wander: Cl_beta z sd 5.6); a
#   ramp of fixed width for how the pot samples a transition (10 ms: 1 seed of 20 beyond
#   3 sigma; 6 and 12 ms: 9 and 3 seeds, the fit stops at different sample crossings).
# - longitudinal: with the a priori CL_q and Cm_alphadot kept through the equation-error
#   start (once overwritten by noisy regression values: CL_de 171 % scatter), 20 seeds:
#   CL_alpha, CL_de, Cm_q z mean +0.1/+0.6/-0.6, sd 0.7-0.9; Cm_alpha, Cm_de z mean
#   -1.1/-1.4, sd 1.3/1.2; CD_alpha, seen only through the 0.8 m/s airspeed noise,
#   +1.3 (bound 59 %). The elevator as a multistep did not help: Cm_alpha z sd 1.6, 4
#   seeds beyond 3 sigma (1, 2, 11, 18), the elevator exact (truth): z sd 1.4, so the
#   Cm_alpha scatter is not the elevator's. Noise-free the model reads Cm_alpha
#   +2.2/+4.3 % at 100/25 Hz (equation error on the same flight: -1.1780 for -1.178).
# Not causes (10 seeds each): the engine vibration (aliases at 19.8 and 39.7 Hz, 1400
# times down after the 8 Hz filter), the gyro random walk, the sensor biases.
# Twin Otter seed 2 Cn_r -3.02 sigma (-0.1911 against -0.1906, 0.3 %) since the JSBSim
# actuators run at the model's own 400 Hz step (sim/jsbsim/model.py sets the step before the
# aircraft loads; they ran at JSBSim's default 120 Hz, 3.3 times too fast, before): the
# surface responses changed by a few ms and moved this one estimate past the line.
# Since 2026-11-27 the colored bounds put back what the fit took out of the residual
# (identification.engine.bounds: leverage); with them that Cn_r is inside 3 sigma.
KNOWN: set[tuple[str, int, str]] = set()


def test_fits_converge_and_estimate_the_main_derivatives(flight):
    card, seed, estimates, rows, _ = flight
    assert all(e.fit.get("converged") for e in estimates)
    lift = "CZ_alpha" if card.sensors.name == "research" else "CL_alpha"  # 6-DOF: body axes
    assert set(WELL_EXCITED) | {"Cm_q", lift, "Cl_beta"} <= set(rows)


def test_estimates_within_3_corrected_sigma_of_truth(flight):
    # 3 colored-residual-corrected Cramer-Rao bounds (M&K 2016 eq. 6.54) hold 99.7 % of a
    # correct estimator's errors; KNOWN lists the measured exceptions (own test below)
    card, seed, _, rows, _ = flight
    bad = {n: f"{(v - t) / s:+.2f} sigma ({v:.4g} vs {t:.4g})" for n, (v, s, t) in rows.items()
           if (card.name, seed, n) not in KNOWN and abs(v - t) >= 3 * s}
    assert not bad, bad


def test_a_priori_derivatives_stay_at_their_values(flight):
    # CL_q and Cm_alphadot are not estimated on the hobby card: they keep the a priori
    # values through the equation-error start (which once overwrote them, see KNOWN)
    card, _, estimates, _, truth = flight
    if card.sensors.name == "research":
        pytest.skip("the 6-DOF fit estimates every derivative")
    fixed = estimates[0].fit["fixed"]
    assert {n: fixed[n] for n in A_PRIORI} == {n: truth[n] for n in A_PRIORI}


def test_known_exceptions_still_fail(flight):
    # strict record of what is not solved: when a fix lands, this fails and KNOWN shrinks
    card, seed, _, rows, _ = flight
    mine = [n for (c, s, n) in KNOWN if (c, s) == (card.name, seed)]
    fixed = [n for n in mine if abs(rows[n][0] - rows[n][2]) < 3 * rows[n][1]]
    assert not fixed, f"now within 3 sigma, remove from KNOWN: {fixed}"


def test_well_excited_derivatives_within_relative_tolerance(flight):
    card, seed, _, rows, _ = flight
    tol = RELATIVE[card.aircraft]
    bad = {n: f"{100 * (rows[n][0] / rows[n][2] - 1):+.1f} %" for n in WELL_EXCITED
           if (card.aircraft, n) not in NO_RELATIVE
           and abs(rows[n][0] / rows[n][2] - 1) >= tol}
    assert not bad, bad
