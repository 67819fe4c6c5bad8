"""The one flight loop: wind hooks, progress, calm-air fill-in, step fast path, rpm, resets."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flightid.sim.flight import disturbed as dist
from flightid.sim.flight.controls import interp_point
from flightid.sim.flight.simulation import Atmosphere, Simulation, fly
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.sim.sensors.builtin import hobby_suite
from flightid.sim.sensors.suites import measure
from flightid.units import DEG, FT

RATE = 50.0


@pytest.fixture(scope="module")
def navion():
    model = load("navion")
    return model, trim(model, 500.0, 53.64)


def _gust(n: int, start: int, width: int, down: float) -> np.ndarray:
    """n x 3 NED: a 1-cosine vertical gust of ``width`` samples from sample ``start``."""
    g = np.zeros((n, 3))
    g[start:start + width, 2] = down * 0.5 * (1 - np.cos(2 * np.pi * np.arange(width) / width))
    return g


def test_stepping_by_hand_reproduces_every_channel_of_a_gusty_flight(navion):
    # fly() fills in the aero rates, the turbulence and the total wind instead of reading
    # them (JSBSim's turbulence is off); step() reads them from JSBSim: every channel of
    # the two must agree, so the fill-in is what JSBSim computes. fly() writes the gust at
    # each JSBSim substep, linear between the record's samples: by hand, one step() per
    # substep (a simulation at the internal rate) with the interpolated gust, the
    # interval's new controls set before its last substep as fly() sets them
    model, tr = navion
    n = int(2.0 * RATE) + 1
    gust = _gust(n, 20, 40, -4.0)
    de = np.where((np.arange(n) >= 10) & (np.arange(n) < 30), 2 * DEG, 0.0)
    wind = Atmosphere(wind_ned_m_s=(3.0, -2.0, 0.5))
    rec = fly(model, tr, {"de": de}, 2.0, RATE, atmosphere=wind, wind=gust)
    substeps = Simulation(model, rate_hz=RATE).substeps
    sim = Simulation(model, rate_hz=RATE * substeps, atmosphere=wind)
    assert sim.substeps == 1
    sim.reset(tr, {"de": de[0]})
    gust_fps = gust / FT
    samples = []
    for k in range(1, n):
        for s in range(1, substeps + 1):
            f = s / substeps
            for i, axis in enumerate(("north", "east", "down")):
                sim.set(f"atmosphere/gust-{axis}-fps",
                        (1.0 - f) * gust_fps[k - 1, i] + f * gust_fps[k, i])
            sample = sim.step({"de": de[k] if s == substeps else de[k - 1]})
        samples.append(sample)
    assert set(samples[0]) == set(rec.channels)
    for name in rec.channels:
        stepped = np.array([s[name] for s in samples])
        scale = max(1.0, float(np.max(np.abs(rec[name]))))
        np.testing.assert_allclose(stepped, rec[name][1:], rtol=0, atol=1e-13 * scale,
                                   err_msg=name)
    # until the gust arrives the flight is the one without it
    still = fly(model, tr, {"de": de}, 2.0, RATE, atmosphere=wind)
    for name in ("alpha", "V", "q", "az"):
        np.testing.assert_array_equal(rec[name][:21], still[name][:21])
    # the gust is booked as wind (steady part + gust), the aircraft feels it in alpha
    np.testing.assert_allclose(rec["wind_down"], 0.5 + gust[:, 2], atol=1e-12)
    assert np.max(rec["alpha"]) - rec["alpha"][0] > 1.5 * DEG


def test_turbulence_schedule_is_booked_as_turbulence_in_body_axes(navion):
    model, tr = navion
    n = int(2.0 * RATE) + 1
    rng = np.random.default_rng(5)
    turb = np.cumsum(rng.normal(0.0, 0.2, (n, 3)), axis=0)
    rec = fly(model, tr, {}, 2.0, RATE, turbulence=turb)
    assert np.max(np.abs(rec["wind_north"])) < 1e-12 and np.max(np.abs(rec["wind_down"])) < 1e-12
    # body components rotate back to the NED schedule with the recorded attitude
    phi, th, psi = rec["phi"], rec["theta"], rec["psi"]
    body = np.stack([rec["turb_u"], rec["turb_v"], rec["turb_w"]], axis=1)
    for k in (0, n // 2, n - 1):
        cf, sf, ct, st, cp, sp = (math.cos(phi[k]), math.sin(phi[k]), math.cos(th[k]),
                                  math.sin(th[k]), math.cos(psi[k]), math.sin(psi[k]))
        dcm = np.array([[ct * cp, ct * sp, -st],
                        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
                        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct]])
        np.testing.assert_allclose(dcm.T @ body[k], turb[k], atol=1e-12)


def test_fly_disturbed_is_the_same_loop(navion):
    model, tr = navion
    n = int(3.0 * RATE) + 1
    gusts, turb = dist.wind_schedule([dist.Turbulence(sigma=1.0, scale_length=100.0),
                                      dist.Gust(start=1.0, rise=0.5, fall=0.5, east=2.0)],
                                     n, RATE, tr, np.random.default_rng(2))
    controls = {"da": np.where(np.arange(n) > 20, 1 * DEG, 0.0)}
    a = dist.fly_disturbed(model, tr, controls, 3.0, RATE, wind=gusts, turbulence=turb)
    b = fly(model, tr, controls, 3.0, RATE, wind=gusts, turbulence=turb)
    for name in a.channels:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    with pytest.raises(ValueError, match=r"control 'da' has \(10,\) samples, the flight needs"):
        dist.fly_disturbed(model, tr, {"da": np.zeros(10)}, 3.0, RATE)


def test_progress_is_reported_every_second_and_bad_schedules_are_named(navion):
    model, tr = navion
    calls = []
    rec = fly(model, tr, {}, 3.0, RATE, progress=lambda k, n: calls.append((k, n)))
    assert calls == [(50, 151), (100, 151), (150, 151)] and len(rec) == 151
    with pytest.raises(ValueError, match=r"wind schedule has shape \(10, 3\), needs \(51, 3\)"):
        fly(model, tr, {}, 1.0, RATE, wind=np.zeros((10, 3)))
    bad = np.zeros((51, 3))
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match="turbulence schedule has non-finite values"):
        fly(model, tr, {}, 1.0, RATE, turbulence=bad)


def test_a_simulation_flies_again_identically_and_its_nodes_follow_resets(navion):
    model, tr = navion
    sim = Simulation(model, rate_hz=RATE)
    de = {"de": lambda t: 2 * DEG if 0.2 <= t < 0.6 else 0.0}
    first = sim.fly(tr, de, 1.0)
    fdm_before = sim.model.fdm
    second = sim.fly(tr, de, 1.0)  # reset gives the model a fresh FGFDMExec
    assert sim.model.fdm is not fdm_before and sim.time == pytest.approx(1.0)
    for name in ("q", "alpha", "V", "az"):
        np.testing.assert_array_equal(first[name], second[name])
    # get/set resolve on the current FGFDMExec: after another reset they still act
    sim.reset(tr)
    sim.set("fcs/elevator-cmd-norm", sim.get("fcs/elevator-cmd-norm") + 0.2)
    s = None
    for _ in range(5):
        s = sim.step()  # step() writes the trim command again before the last substep
    assert s["q"] == sim.get("velocities/q-rad_sec")
    assert s["V"] == pytest.approx(sim.get("velocities/vt-fps") * FT, rel=1e-15)


def test_scalar_interpolation_is_numpys_to_the_bit():
    rng = np.random.default_rng(11)
    xp = np.unique(np.concatenate([np.linspace(-0.5, 0.4, 81), rng.uniform(-0.5, 0.4, 5)]))
    fp = np.tanh(3 * xp) + 0.1 * xp
    fp[20:25] = fp[20]  # a plateau
    x = np.concatenate([rng.uniform(-0.7, 0.6, 2000), xp, [xp[0], xp[-1], -1.0, 1.0]])
    ours = np.array([interp_point(float(v), xp.tolist(), fp.tolist()) for v in x])
    np.testing.assert_array_equal(ours, np.interp(x, xp, fp))


def test_telemaster_records_its_propeller_rpm_and_the_hobby_suite_vibrates():
    # the Telemaster publishes fcs/propeller-rpm = 1700 + 8300 x throttle command
    # (aircraft/telemaster/telemaster.xml, thesis App. 3)
    model = load("telemaster")
    tr = trim(model, 30.0, 15.0)
    step = np.where(np.arange(201) >= 100, 0.3, 0.0)
    rec = fly(model, tr, {"throttle": step}, 2.0, 100.0)
    assert "rpm" in rec.channels
    # (the model's fcs/throttle-pos-norm carries its thrust / 20 lbf, so the law is checked
    # against the commanded throttle; the command acts from its own sample on)
    np.testing.assert_allclose(rec["rpm"], 1700.0 + 8300.0 * (tr.throttle + step), rtol=1e-12)
    # the full hobby suite (engine vibration driven by rpm, rpm quantised to 100 rpm) works
    measured = measure(rec, hobby_suite(), seed=3)
    err = measured["rpm"] - np.interp(measured.time, rec.time, rec["rpm"])
    assert np.max(np.abs(err[measured.time < 0.9])) <= 50.0 + 1e-9


def test_navion_rpm_is_its_propellers(navion):
    model, tr = navion
    rec = fly(model, tr, {}, 0.5, RATE)
    assert rec["rpm"][0] == pytest.approx(model.get("propulsion/engine[0]/propeller-rpm"),
                                          rel=0.05)
    assert 1500.0 < rec["rpm"][0] < 3000.0  # a light aircraft's propeller


@pytest.mark.parametrize("severity,poe_sigma_fps", [
    # MIL-F-8785C Fig. 7 at 9843 ft, between its 7500 and 15000 ft points (the curves
    # JSBSim tabulates in FGWinds): POE 1e-2 6.7 -> 4.6 ft/s, POE 1e-3 10.1 -> 8.0 ft/s
    (3, 6.7 + (9843 - 7500) / 7500 * (4.6 - 6.7)),
    (4, 10.1 + (9843 - 7500) / 7500 * (8.0 - 10.1)),
])
def test_jsbsim_severity_3_is_light_and_4_moderate(severity, poe_sigma_fps):
    model = load("twinotter")
    tr = trim(model, 3000.0, 70.0)  # above 2000 ft: sigma from the POE curve alone
    atm = Atmosphere(turbulence="milspec", severity=severity, seed=severity)
    rec = fly(model, tr, {}, 600.0, 5.0, atmosphere=atm)
    sigma = float(np.std(rec["turb_w"]))
    # L = 1750 ft at 70 m/s: correlation time Tc ~ 8 s; over T = 600 s the sample sigma
    # scatters by sqrt(Tc / (2 T)) ~ 8 %: 25 % is about three standard deviations, and the
    # neighbouring curves at this height are 1.5 times apart (POE 1e-4: 14.0 ft/s)
    assert sigma == pytest.approx(poe_sigma_fps * FT, rel=0.25)


def _side_gust(t: np.ndarray) -> np.ndarray:
    """n x 3 NED: a smooth east gust (m/s), two sines at 0.7 and 2.3 Hz."""
    g = np.zeros((len(t), 3))
    g[:, 1] = 1.0 * np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 2.3 * t + 1.0)
    return g


def test_the_gust_booked_at_a_sample_is_the_one_acting_there(navion):
    # a continuous gust sampled on a 100 Hz record grid flies as the same gust sampled at
    # JSBSim's 400 Hz internal rate: fly() writes it at each substep, linear between the
    # record's samples, so the gust part of the recorded sideslip and the response it
    # drives agree in time (a vane has no lag). A value held over the substeps would lead
    # the record by half a record step: its flight is the fine one with g(t + h/2).
    model, tr = navion
    duration, rate = 5.0, 100.0
    fine_rate = rate * Simulation(model, rate_hz=rate).substeps
    assert Simulation(model, rate_hz=fine_rate).substeps == 1
    t, t_fine = np.arange(501) / rate, np.arange(2001) / fine_rate
    rec = fly(model, tr, {}, duration, rate, turbulence=_side_gust(t))
    fine = fly(model, tr, {}, duration, fine_rate, turbulence=_side_gust(t_fine))
    lead = fly(model, tr, {}, duration, fine_rate,
               turbulence=_side_gust(t_fine + 0.5 / rate))
    every = int(fine_rate / rate)
    np.testing.assert_allclose(rec["turb_v"], fine["turb_v"][::every], atol=1e-12)
    err = rec["beta"] - fine["beta"][::every]
    err_lead = lead["beta"][::every] - fine["beta"][::every]
    # linear interpolation misses the gust by at most |g''| h^2 / 8 = (1 * (1.4 pi)^2
    # + 0.5 * (4.6 pi)^2) * 0.01^2 / 8 = 1.5e-3 m/s: 2.9e-5 rad of sideslip at 53.6 m/s
    # (measured: 3e-6 rad). The half-step lead moves the gust by up to |g'| h / 2 =
    # (4.4 + 7.2) * 0.005 = 0.058 m/s (its sideslip differs by 6e-4 rad rms); a held value
    # (gust k over the substeps before t_k) leaves 9e-5 rad rms, 1.9e-4 rad at most
    assert np.max(np.abs(err)) < 3e-5
    assert np.sqrt(np.mean(err**2)) < 0.05 * np.sqrt(np.mean(err_lead**2))
    assert np.std(rec["beta"]) > 0.5 * DEG  # the gust is felt: about 1 m/s / V
