"""Sensor effects, mounting, vibration and suites: recover what was injected."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from scipy.signal import butter, sosfiltfilt

from flightid.record import FlightRecord, RecordMeta
from flightid.record import read as read_record
from flightid.sim.effects import CATALOGUE, EFFECTS, Lag, SecondOrder, effect_from_dict
from flightid.sim.effects.vibration import EngineVibration
from flightid.sim.sensors.builtin import builtin_suite
from flightid.sim.sensors.suites import LeverArm, SensorSuite, Vanes, measure
from flightid.sim.sensors.tables import suite_from_dict
from flightid.units import G0


def smooth_truth(duration: float, fs: float, seed: int, rpm: float = 16000.0) -> FlightRecord:
    """Smooth band-limited (1.5 Hz) flight-like signals at ``fs`` Hz: a stand-in truth."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs) + 1) / fs
    sos = butter(2, 1.5, fs=fs, output="sos")

    def sig(scale: float, mean: float = 0.0) -> np.ndarray:
        x = sosfiltfilt(sos, rng.standard_normal(t.size))
        return mean + scale * x / x.std()

    ch = {
        "V": sig(1.0, 25.0),
        "qbar": sig(20.0, 380.0),
        "alpha": sig(0.03, 0.06),
        "beta": sig(0.03),
        "p": sig(0.3),
        "q": sig(0.2),
        "r": sig(0.1),
        "ax": sig(0.5),
        "ay": sig(0.5),
        "az": sig(1.0, -G0),
        "phi": sig(0.2),
        "theta": sig(0.1, 0.05),
        "psi": sig(0.1),
        "h": sig(2.0, 300.0),
        "de": sig(0.03),
        "da": sig(0.03),
        "dr": sig(0.03),
        "throttle": sig(0.05, 0.6),
        "thrust": sig(5.0, 40.0),
        "L_prop": sig(1.0),
        "M_prop": sig(1.0),
        "N_prop": sig(1.0),
        "latitude": 0.7 + 0 * t,
        "longitude": 0.2 + 0 * t,
        "rpm": rpm + 0 * t,
        "mass": 10 + 0 * t,
        "Ixx": 1 + 0 * t,
        "Iyy": 2 + 0 * t,
        "Izz": 3 + 0 * t,
        "Ixz": 0 * t,
    }
    for a in "pqr":
        ch[a + "dot"] = np.gradient(ch[a], t)
    return FlightRecord(t, ch, RecordMeta(aircraft="synthetic", sample_rate=fs))


@pytest.fixture(scope="module")
def long_truth() -> FlightRecord:
    return smooth_truth(600.0, 200.0, seed=3)  # 600 s, sampled at 100 Hz below


def one(channel: str, *effects: dict) -> SensorSuite:
    return suite_from_dict({"channels": {channel: [*effects]}})


@pytest.mark.parametrize("channel, sigma", [("q", 0.02), ("az", 0.3), ("alpha", 0.01)])
def test_noise_sigma_and_bias_recovered_within_5_percent(long_truth, channel, sigma):
    suite = one(
        channel,
        {"effect": "sample", "rate": 100},
        {"effect": "bias", "value": 0.5 * sigma},
        {"effect": "noise", "sigma": sigma},
    )
    m = measure(long_truth, suite, seed=11)
    assert m.meta.sample_rate == 100 and len(m) == 60001
    err = m[channel] - np.interp(m.time, long_truth.time, long_truth[channel])
    # 60,000 samples: the sample std is within 0.3 % (1 sigma) of sigma, the mean within
    # sigma / sqrt(N) = 0.8 % of the bias
    assert err.std() == pytest.approx(sigma, rel=0.05)
    assert err.mean() == pytest.approx(0.5 * sigma, rel=0.05)


@pytest.mark.parametrize("tau", [0.043, 0.12])
def test_delay_recovered_by_least_squares_shift(long_truth, tau):
    suite = one(
        "p",
        {"effect": "delay", "tau": tau},
        {"effect": "sample", "rate": 100},
        {"effect": "noise", "sigma_deg": 0.5},
    )
    m = measure(long_truth, suite, seed=5)

    def cost(d: float) -> float:
        return float(
            np.sum((m["p"] - np.interp(m.time - d, long_truth.time, long_truth["p"])) ** 2)
        )

    est = minimize_scalar(cost, bounds=(0.0, 0.3), method="bounded", options={"xatol": 1e-5}).x
    assert est == pytest.approx(tau, rel=0.05)


def test_random_walk_and_drift_recovered(long_truth):
    suite = one(
        "r",
        {"effect": "sample", "rate": 100},
        {"effect": "random_walk", "sigma": 0.002},
        {"effect": "drift", "rate": 1e-4},
    )
    m = measure(long_truth, suite, seed=2)
    err = m["r"] - np.interp(m.time, long_truth.time, long_truth["r"])
    inc = np.diff(err)
    dt = 0.01
    assert np.sqrt(np.var(inc) / dt) == pytest.approx(0.002, rel=0.05)
    # the linear drift is the mean increment; its standard error is 0.002 sqrt(600) / 600
    assert inc.mean() / dt == pytest.approx(1e-4, abs=3 * 0.002 / np.sqrt(600))


def test_scale_quantization_saturation():
    t = np.linspace(0, 10, 1001)
    x = np.sin(t)
    rng = np.random.default_rng(0)
    y = effect_from_dict({"effect": "scale", "factor": 1.06}).apply(t, x, rng)
    assert np.polyfit(x, y, 1)[0] == pytest.approx(1.06, rel=1e-12)
    q = effect_from_dict({"effect": "quantize", "resolution": 0.05}).apply(t, x, rng)
    assert np.allclose(q / 0.05, np.round(q / 0.05)) and np.abs(q - x).max() <= 0.025 + 1e-12
    s = effect_from_dict({"effect": "saturate", "limit": 0.5}).apply(t, x, rng)
    assert s.max() == 0.5 and s.min() == -0.5


def test_lag_and_second_order_step_responses():
    t = np.arange(0, 2, 1e-3)
    step = (t >= 0.1).astype(float)
    y = Lag(tau=0.05).apply(t, step, None)
    # first-order hold: the sampled step is a ramp over the sample before t = 0.1 s,
    # which acts as a step at its midpoint, 0.0995 s
    assert np.interp(0.15, t, y) == pytest.approx(1 - np.exp(-(0.15 - 0.0995) / 0.05), abs=1e-4)
    v = SecondOrder(wn=108.0, zeta=0.19).apply(t, step, None)
    overshoot = v.max() - 1
    # peak overshoot of a second-order system exp(-zeta pi / sqrt(1 - zeta^2))
    assert overshoot == pytest.approx(np.exp(-0.19 * np.pi / np.sqrt(1 - 0.19**2)), rel=0.02)


def test_lever_arm_centripetal_and_tangential():
    t = np.arange(0, 5, 0.01)
    r = 0.5 + 0.2 * t  # yaw rate rising: rdot = 0.2
    zeros = 0 * t
    ch = {
        "ax": zeros,
        "ay": zeros,
        "az": zeros - G0,
        "p": zeros,
        "q": zeros,
        "r": r,
        "pdot": zeros,
        "qdot": zeros,
        "rdot": zeros + 0.2,
    }
    out = LeverArm(x=0.4).apply_record(t, ch, None)
    assert np.allclose(out["ax"], -(r**2) * 0.4)  # centripetal towards the CG
    assert np.allclose(out["ay"], 0.2 * 0.4)  # tangential rdot x
    assert np.allclose(out["az"], -G0)


def test_vanes_kinematic_and_upwash(long_truth):
    tr = long_truth.slice(0, 60)
    out = Vanes(alpha_x=1.0, beta_x=1.0, beta_z=-0.3, upwash=0.06, sidewash=0.1).apply_record(
        tr.time, tr.channels, None
    )
    V, q, p, r = tr["V"], tr["q"], tr["p"], tr["r"]
    lin_a = 1.06 * (tr["alpha"] - 1.0 * q / V)  # ARL FM Report 187: K_a (alpha - x_a q / V)
    lin_b = 1.10 * (tr["beta"] + 1.0 * r / V + 0.3 * p / V)  # K_b (beta - z_b p/V + x_b r/V)
    # exact local-flow angles differ from the linear form by second-order terms
    assert np.abs(out["alpha"] - lin_a).max() < 2e-3
    assert np.abs(out["beta"] - lin_b).max() < 2e-3
    assert np.abs(out["alpha"] - 1.06 * tr["alpha"]).max() > 5e-3  # the effect is there


def _line_db(t: np.ndarray, x: np.ndarray, f_line: float) -> float:
    """Level (dB) of the spectral line at f_line over the median floor within +-5 Hz."""
    n = x.size
    win = np.hanning(n)
    P = np.abs(np.fft.rfft((x - x.mean()) * win)) ** 2
    f = np.fft.rfftfreq(n, t[1] - t[0])
    line = P[np.abs(f - f_line) < 0.1].max()
    near = (np.abs(f - f_line) < 5) & (np.abs(f - f_line) > 0.5)
    return 10 * np.log10(line / np.median(P[near]))


@pytest.mark.parametrize(
    "rpm, rate, antialias, f_seen",
    [
        (16000.0, 100.0, 0.0, 100 / 3),  # 266.7 Hz aliases to |266.7 - 3 x 100| = 33.3 Hz
        (16000.0, 1000.0, 0.0, 800 / 3),  # a fast sensor sees the true line
        (9300.0, 100.0, 0.0, 45.0),  # 155 Hz aliases to 45 Hz
    ],
)
def test_vibration_line_at_rotation_or_alias(rpm, rate, antialias, f_seen):
    truth = smooth_truth(60.0, 200.0, seed=1, rpm=rpm)
    chain = [
        {"effect": "sample", "rate": rate, "antialias": antialias},
        {"effect": "noise", "sigma_g": 0.02},
    ]
    vib = {"effect": "engine_vibration", "az": 2.0, "harmonics": 1}
    on = measure(truth, suite_from_dict({"channels": {"az": chain}, "mounting": [vib]}), seed=4)
    off = measure(truth, suite_from_dict({"channels": {"az": chain}}), seed=4)
    assert _line_db(on.time, on["az"], f_seen) >= 20
    assert _line_db(off.time, off["az"], f_seen) < 10


def test_antialias_filter_removes_the_vibration_line():
    truth = smooth_truth(60.0, 200.0, seed=1)
    chain = [
        {"effect": "sample", "rate": 100, "antialias": 20, "order": 4},
        {"effect": "noise", "sigma_g": 0.02},
    ]
    vib = {"effect": "engine_vibration", "az": 2.0}
    m = measure(truth, suite_from_dict({"channels": {"az": chain}, "mounting": [vib]}), seed=4)
    assert _line_db(m.time, m["az"], 100 / 3) < 10


@pytest.mark.parametrize("truth_rate", [50.0, 200.0])
def test_vibration_leaves_every_channel_with_the_same_filters(truth_rate):
    """With an engine vibration every channel is filtered on the vibration's fine grid: a
    channel without vibration (q) and a vibrating one (az, at 1e-9 m/s^2) that carry the
    same truth signal come out equal, as without any vibration. Filtering only the
    vibrating ones finely left them 3.2 % (50 Hz truth) and 0.14 % (200 Hz) of the signal's
    rms apart: the 10 Hz filter's delay differs between the truth's grid and the fine one."""
    truth = smooth_truth(20.0, truth_rate, seed=3, rpm=2100.0)
    truth = truth.with_channels(q=truth["az"] - truth["az"].mean())
    truth = truth.with_channels(az=truth["q"])
    chain = [{"effect": "sample", "rate": 50, "antialias": 10, "order": 4}]
    vib = {"effect": "engine_vibration", "az": 1e-9}
    m = measure(truth, suite_from_dict({"channels": {"az": chain, "q": chain},
                                        "mounting": [vib]}), seed=4)
    spread = float(np.sqrt(np.mean(m["q"] ** 2)))
    assert float(np.max(np.abs(m["az"] - m["q"]))) < 1e-8 * spread + 1e-8


def test_vibration_phase_follows_a_varying_rpm():
    t = np.arange(0, 10, 1e-4)
    rpm = 6000 + 600 * t  # 100 Hz rising at 10 Hz/s
    v = EngineVibration(az=1.0)
    x = v.signal(t, rpm, "az", np.zeros((6, 1)))
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    crossings = t[i] + (t[i + 1] - t[i]) * (-x[i]) / (x[i + 1] - x[i])
    f_meas = 1 / np.diff(crossings)
    f_law = np.interp(crossings[:-1] + np.diff(crossings) / 2, t, rpm / 60)
    assert np.abs(f_meas / f_law - 1).max() < 2e-3


def test_same_seed_same_output_and_independent_channel_streams():
    truth = smooth_truth(20.0, 200.0, seed=9)
    suite = builtin_suite("hobby")
    a, b, c = measure(truth, suite, 1), measure(truth, suite, 1), measure(truth, suite, 2)
    for k in a.channels:
        assert np.array_equal(a[k], b[k])
    assert not np.array_equal(a["q"], c["q"])
    # removing a channel does not change another channel's noise
    fewer = suite_from_dict({"base": "hobby"})
    del fewer.channels["p"]
    d = measure(truth, fewer, 1)
    assert np.array_equal(d["q"], a["q"])


def test_builtin_suites_end_to_end_and_file_round_trip(tmp_path):
    truth = smooth_truth(30.0, 400.0, seed=4)
    for name in ("hobby", "research", "ideal"):
        m = measure(truth, builtin_suite(name), seed=0)
        assert all(np.all(np.isfinite(v)) for v in m.channels.values())
        info = m.meta.extra["measurement"]
        assert info["suite"] == name and info["output_rate_hz"] == m.meta.sample_rate
        path = m.write(tmp_path / f"{name}.parquet")
        back = read_record(path)
        assert back.meta.extra["measurement"]["resampling"] == info["resampling"]
        assert np.array_equal(back["q"], m["q"])
    hobby = measure(truth, builtin_suite("hobby"), seed=0)
    # 25 Hz vane channels are held over 4 output samples of 100 Hz
    steps = np.nonzero(np.diff(hobby["alpha"]))[0]
    assert np.all(np.diff(steps) % 4 == 0)
    # research: Twin Otter noise levels are tiny, so q is the truth delayed by the 4-pole
    # 10 Hz Butterworth anti-alias filter, whose low-frequency group delay is
    # 2.6131 / (2 pi 10 Hz) = 41.6 ms
    res = measure(truth, builtin_suite("research"), seed=0)
    delayed = np.interp(res.time - 2.6131 / (2 * np.pi * 10), truth.time, truth["q"])
    err = (res["q"] - delayed)[res.time > 1]
    assert np.abs(err).max() < 0.01 * np.abs(truth["q"]).max()


def test_every_effect_round_trips_through_its_dict():
    for name, cls in EFFECTS.items():
        e = cls()
        again = effect_from_dict(e.to_dict())
        assert again == e and again.parameters() == e.parameters(), name
    s = builtin_suite("hobby")
    again = suite_from_dict(s.to_dict())
    assert again.to_dict() == s.to_dict()
    # mounting and vibration effects too, through the catalogue's card section
    for m in builtin_suite("hobby").mounting:
        assert CATALOGUE.from_dict(m.to_dict(), "mounting") == m


def test_effects_at_their_neutral_infinity_leave_the_signal_alone():
    t = np.arange(200) / 100.0
    x = np.sin(2 * np.pi * 1.3 * t)
    rng = np.random.default_rng(0)
    for d in ({"effect": "saturate", "limit": np.inf}, {"effect": "lowpass", "cutoff": np.inf},
              {"effect": "second_order", "wn": np.inf}, {"effect": "sample", "rate": np.inf}):
        np.testing.assert_array_equal(effect_from_dict(d).apply(t, x, rng), x)
    # a continuous sampler is not a sampled channel: no zero-order hold at the output
    suite = one("q", {"effect": "sample", "rate": np.inf})
    assert suite.sample_rate("q") is None


@pytest.mark.parametrize(
    "d, field",
    [
        ({"channels": {"q": [{"effect": "noise", "sigma": "big"}]}}, "channels.q[0].sigma"),
        ({"channels": {"q": [{"effect": "nois"}]}}, "channels.q[0].effect"),
        ({"channels": {"q": [{"sigma": 1}]}}, "channels.q[0].effect"),
        ({"channels": {"q": [{"effect": "noise", "sigma": -1}]}}, "'sigma'"),
        ({"channels": {"q": [{"effect": "noise", "sigmа": 1}]}}, "channels.q[0].sigmа"),
        ({"channels": {"ax": [{"effect": "noise", "sigma_deg": 1}]}}, "channels.ax[0].sigma_deg"),
        ({"channels": {"q": [{"effect": "bias", "value_g": 1}]}}, "channels.q[0].value_g"),
        ({"channels": {"qq": []}}, "channels.qq"),
        ({"channels": {"q": {"effect": "noise"}}}, "channels.q"),
        ({"mounting": [{"effect": "lever_arm", "w": 1}]}, "mounting[0].w"),
        ({"mounting": [{"effect": "boom"}]}, "mounting[0].effect"),
        ({"base": "spacecraft"}, "'base'"),
        ({"outputrate": 10}, "'outputrate'"),
        ({"channels": {"q": [{"effect": "sample", "rate": 0}]}}, "'rate'"),
        # names resolve through the catalogue: a sample rate is in Hz, not in the channel unit
        ({"channels": {"q": [{"effect": "sample", "rate_deg": 5}]}}, "channels.q[0].rate_deg"),
        ({"channels": {"q": [{"effect": "bias", "value": np.inf}]}}, "channels.q[0].value"),
        ({"channels": {"q": [{"effect": "wind"}]}}, "channels.q[0].effect"),
        ({"mounting": [{"effect": "noise"}]}, "mounting[0].effect"),
        ({"mounting": [{"effect": "vanes", "upwash": -2.0}]}, "mounting[0].upwash"),
    ],
)
def test_bad_suite_dicts_name_the_field(d, field):
    with pytest.raises(ValueError, match=re.escape(field)):
        suite_from_dict(d)


def test_missing_truth_channels_are_named():
    truth = smooth_truth(5.0, 100.0, seed=0)
    no_rpm = FlightRecord(truth.time, {k: v for k, v in truth.channels.items() if k != "rpm"})
    with pytest.raises(ValueError, match="'rpm'"):
        measure(
            no_rpm,
            suite_from_dict(
                {"channels": {"az": []}, "mounting": [{"effect": "engine_vibration", "az": 1}]}
            ),
        )
    with pytest.raises(ValueError, match="lacks"):
        measure(FlightRecord(truth.time, {"q": truth["q"]}), builtin_suite("research"))
