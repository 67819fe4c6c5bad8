"""Disturbances: turbulence intensity and effect, steady wind, discrete gusts (real JSBSim)."""

from __future__ import annotations

import numpy as np
import pytest

from flightid.sim.effects.vibration import EngineVibration
from flightid.sim.flight import disturbed as dist
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim
from flightid.units import DEG, FT, KT


def _fly(aircraft, altitude, speed, disturbances, duration, rate, seed=0, controls=None):
    model = load(aircraft)
    tr = trim(model, altitude, speed)
    n = int(round(duration * rate)) + 1
    gusts, turb = dist.wind_schedule(disturbances, n, rate, tr, np.random.default_rng(seed))
    return dist.fly_disturbed(model, tr, controls or {}, duration, rate,
                              dist.atmosphere_for(disturbances, seed), wind=gusts,
                              turbulence=turb)


@pytest.mark.parametrize("aircraft,altitude,speed,form,seed", [
    ("navion", 1500.0, 53.64, "dryden", 1),
    ("navion", 0.0, 53.64, "dryden", 2),
    ("twinotter", 1890.0, 72.2, "von_karman", 3),
])
def test_turbulence_variance_is_the_requested_sigma_squared(aircraft, altitude, speed, form,
                                                             seed):
    sigma, scale = 1.5, 50.0
    rec = _fly(aircraft, altitude, speed,
               [dist.Turbulence(model=form, sigma=sigma, scale_length=scale)], 400.0, 10.0, seed)
    # the sample variance of a process with correlation time Tc ~ L/V ~ 1 s over T = 400 s
    # scatters by sqrt(2 Tc / T) ~ 7 %: 20 % is about 3 standard deviations
    for axis in "uvw":
        ratio = np.var(rec[f"turb_{axis}"]) / sigma**2
        assert 0.8 < ratio < 1.2, (axis, ratio)
    # our turbulence is booked as turbulence, not as wind
    assert np.max(np.abs(rec["wind_north"])) < 1e-9


def test_turbulence_changes_the_response():
    calm = _fly("navion", 0.0, 53.64, [], 30.0, 50.0)
    rough = _fly("navion", 0.0, 53.64, [dist.Turbulence(intensity="light")], 30.0, 50.0, 4)
    # light turbulence at 300 m above ground: sigma_w = 0.1 W20 = 0.77 m/s, about 0.8 deg
    # of gust angle of attack at 53.6 m/s, mostly below the short period (V / L_w = 0.18
    # rad/s), where the aircraft weathervanes into it: a fraction shows in alpha and q.
    # Calm air stays trimmed.
    assert np.std(calm["alpha"]) < 1e-4 * DEG
    assert np.std(rough["alpha"]) > 0.1 * DEG
    assert np.std(rough["q"]) > 0.1 * DEG
    assert np.std(rough["p"]) > 0.1 * DEG
    assert np.std(rough["turb_w"]) > 0.4


def test_light_turbulence_follows_mil_f_8785c():
    # below 1000 ft: sigma_w = 0.1 W20 (W20 = 15 kt light), L_w = h
    (su, sv, sw), (lu, lv, lw) = dist.mil_f_8785c("light", 300.0)
    h_ft = 300.0 / FT
    assert sw == pytest.approx(0.1 * 15 * KT)
    assert su == pytest.approx(sw / (0.177 + 0.000823 * h_ft) ** 0.4)
    assert lw == pytest.approx(300.0) and lu == pytest.approx(h_ft / (0.177 + 0.000823 * h_ft)
                                                              ** 1.2 * FT)
    # above 2000 ft: Fig. 7 (moderate at 3750 ft: 10.6 ft/s) and L = 1750 ft (Dryden)
    (su, _, sw), (lu, _, lw) = dist.mil_f_8785c("moderate", 3750 * FT)
    assert su == sw == pytest.approx(10.6 * FT)
    assert lu == lw == pytest.approx(1750 * FT)
    assert dist.mil_f_8785c("severe", 3750 * FT, "von_karman")[1][0] == pytest.approx(2500 * FT)


def test_steady_wind_is_the_difference_of_inertial_and_air_velocity():
    calm = _fly("navion", 500.0, 53.64, [], 20.0, 50.0)
    windy = _fly("navion", 500.0, 53.64, [dist.Wind(north=-8.0, east=3.0)], 20.0, 50.0)
    # the air-relative motion does not see a steady wind: the trim holds in the air mass
    # (up to mm/s from the different ground track over the rotating Earth in 20 s)
    np.testing.assert_allclose(windy["V"], calm["V"], atol=0.01)
    np.testing.assert_allclose(windy["alpha"], calm["alpha"], atol=1e-4)
    assert windy["wind_north"] == pytest.approx(np.full(len(windy), -8.0))
    # ground velocity = air velocity + wind; north/east come from latitude and longitude
    # on a sphere of the equatorial radius, good to 0.5 % (WGS-84 flattening)
    dt = windy.dt
    for axis, w in (("north", -8.0), ("east", 3.0)):
        dv = np.mean(np.diff(windy[axis]) - np.diff(calm[axis])) / dt
        assert dv == pytest.approx(w, rel=0.01), axis


def test_gust_arrives_at_the_stated_time():
    gust = dist.Gust(start=5.0, rise=1.0, hold=0.0, fall=1.0, down=-3.0)  # an up-gust
    calm = _fly("navion", 500.0, 53.64, [], 10.0, 100.0)
    rec = _fly("navion", 500.0, 53.64, [gust], 10.0, 100.0)
    t = rec.time
    assert np.all(np.abs(rec["wind_down"][t <= 5.0]) < 1e-12)
    assert rec["wind_down"][np.argmin(np.abs(t - 6.0))] == pytest.approx(-3.0)
    d_alpha = rec["alpha"] - calm["alpha"]
    first = t[np.argmax(np.abs(d_alpha) > 0.01 * DEG)]
    assert 5.0 < first < 5.3
    # 3 m/s up at 53.6 m/s is 3.2 deg of gust angle; in the 1 s rise, comparable to the
    # short period, the aircraft already pitches into it: a third shows in alpha
    assert np.max(d_alpha) > 1.0 * DEG
    assert t[np.argmax(d_alpha)] == pytest.approx(6.0, abs=0.5)


def test_disturbances_build_from_tables_and_name_bad_fields():
    w = dist.disturbance_from_dict({"kind": "wind", "speed": 5.0, "from_deg": 270.0})
    assert (w.north, w.east) == pytest.approx((0.0, 5.0))  # from the west: blows east
    v = dist.disturbance_from_dict({"kind": "engine_vibration", "az": 2.0, "p_deg": 1.0})
    assert isinstance(v, EngineVibration) and v.p == pytest.approx(DEG)
    t = dist.disturbance_from_dict({"kind": "turbulence", "intensity": "moderate"})
    assert t.parameters()["sigma"] == 0.0 and "intensity" not in t.parameters()
    with pytest.raises(ValueError, match="'d\\[0\\].kind'.*unknown disturbance 'hail'"):
        dist.disturbance_from_dict({"kind": "hail"}, "d[0]")
    with pytest.raises(ValueError, match="'d\\[1\\].gain' is not a parameter of 'gust'"):
        dist.disturbance_from_dict({"kind": "gust", "gain": 1.0}, "d[1]")
    with pytest.raises(ValueError, match="'d\\[2\\].intensity'.*'stormy'"):
        dist.disturbance_from_dict({"kind": "turbulence", "intensity": "stormy"}, "d[2]")
    with pytest.raises(ValueError, match="'rise'.*> 0"):
        dist.Gust(start=1.0, rise=0.0)
    # a turbulence table must size it; a sigma of 0 with a scale length is calm air
    with pytest.raises(ValueError, match="'d\\[3\\].intensity'.*give an intensity"):
        dist.disturbance_from_dict({"kind": "turbulence", "scale_length": 100.0}, "d[3]")
    calm = dist.disturbance_from_dict({"kind": "turbulence", "sigma": 0.0,
                                       "scale_length": 100.0})
    assert not np.any(calm.velocities(50, 10.0, 50.0, 300.0, np.random.default_rng(0)))
    # kinds resolve through the effect catalogue: one of another place says where it goes
    with pytest.raises(ValueError, match="'d\\[4\\].kind'.*sensor effect.*sensors.channels"):
        dist.disturbance_from_dict({"kind": "noise"}, "d[4]")
    assert set(dist.DISTURBANCES) == {"wind", "gust", "turbulence", "engine_vibration"}
