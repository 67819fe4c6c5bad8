"""Input designs: exact switching, sweep laws, orthogonal multisines, rate limits, dicts."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.signal import hilbert

from flightid.scenarios.equal_energy import energy, scale_to_energy, spectrum
from flightid.scenarios.input_design import EDGE_TOL, rate_limit
from flightid.scenarios.inputs import (
    INPUT_KINDS,
    Doublet,
    Sweep,
    ThreeTwoOneOne,
    input_from_dict,
    inputs_from_list,
    total_signals,
)
from flightid.scenarios.multisine import (
    Components,
    harmonic_indices,
    relative_peak_factor,
    schroeder_phases,
    split_harmonics,
)
from flightid.units import DEG


@pytest.mark.parametrize(
    "rate, start, base",
    [(100.0, 10.0, 0.5), (50.0, 3.0, 0.3), (64.0, 2.0031, 0.377), (100.0, 1.0, 0.01)],
)
def test_3211_edges_land_on_the_first_sample_at_or_after_each_switch(rate, start, base):
    t = np.arange(int(20 * rate)) / rate
    d = ThreeTwoOneOne(surface="de", start=start, base=base, amplitude=3 * DEG)
    u = d.signal(t)
    switches = start + base * np.cumsum([0, 3, 2, 1, 1])
    levels = [3 * DEG, -3 * DEG, 3 * DEG, -3 * DEG, 0.0]
    for k, (ts, level) in enumerate(zip(switches, levels, strict=True)):
        i = int(np.argmax(t >= ts - EDGE_TOL))
        assert u[i] == level, f"edge {k} at t = {ts}"
        if i > 0:
            assert u[i - 1] == ([0.0] + levels)[k], f"sample before edge {k}"
    assert np.all(u[t < start - EDGE_TOL] == 0)
    assert set(np.unique(u)) <= {0.0, 3 * DEG, -3 * DEG}


def test_other_multisteps_have_their_pulse_widths():
    t = np.arange(2000) / 100.0
    for kind, widths in {"doublet": [1, 1], "21": [2, 1], "211": [2, 1, 1], "pulse": [1]}.items():
        u = input_from_dict(
            {"kind": kind, "surface": "dr", "start": 2, "base": 0.4, "amplitude": 1}
        )
        levels = u.signal(t)
        edges = np.nonzero(np.diff(levels))[0] + 1
        assert np.allclose(np.diff(t[edges]), 0.4 * np.array(widths), atol=1e-9), kind


@pytest.mark.parametrize("law", ["linear", "log"])
@pytest.mark.parametrize("f0, f1", [(0.1, 3.0), (4.0, 0.5)])
def test_sweep_instantaneous_frequency_follows_the_law(law, f0, f1):
    rate = 200.0
    t = np.arange(int(100 * rate)) / rate
    d = Sweep(
        surface="de",
        start=5,
        amplitude=1,
        f_start=f0,
        f_end=f1,
        duration=90,
        law=law,
        fade_in=3,
        fade_out=3,
    )
    u = d.signal(t)
    inst = np.gradient(np.unwrap(np.angle(hilbert(u))), t) / (2 * np.pi)
    # away from the fades and the ends, where the analytic signal is clean, and away
    # from the lowest frequencies, which the Hilbert transform resolves poorly
    tau = (t - 5) / 90
    law_f = f0 + (f1 - f0) * tau if law == "linear" else f0 * (f1 / f0) ** tau
    ok = (t > 15) & (t < 85) & (law_f > 0.3)
    err = np.abs(inst[ok] - law_f[ok]) / law_f[ok]
    assert np.median(err) < 0.005 and err.max() < 0.05
    # the design's own law and phase agree with the formula exactly
    assert np.allclose(d.frequency(t), np.where((t >= 5) & (t <= 95), law_f, d.frequency(t)))
    dphase = np.gradient(d.phase(t), t) / (2 * np.pi)
    mid = (t > 6) & (t < 94)
    assert np.allclose(dphase[mid], d.frequency(t)[mid], rtol=1e-4)


def test_orthogonal_multisines_are_orthogonal_and_beat_schroeder_peak_factor():
    period, rate = 20.0, 100.0
    t = np.arange(int(period * rate)) / rate  # one period
    common = {
        "kind": "orthogonal_multisine",
        "surfaces": ["de", "da", "dr"],
        "f_min": 0.1,
        "f_max": 2.0,
        "period": period,
        "amplitude_deg": 3,
    }
    opt = input_from_dict(common).signals(t)
    sch = input_from_dict({**common, "phases": "schroeder"}).signals(t)
    names = list(opt)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            cos = np.dot(opt[a], opt[b]) / np.linalg.norm(opt[a]) / np.linalg.norm(opt[b])
            assert abs(cos) < 1e-9, (a, b)
    for s in names:
        rpf_opt, rpf_sch = relative_peak_factor(opt[s]), relative_peak_factor(sch[s])
        assert rpf_opt < rpf_sch - 0.05, s
        assert rpf_opt < 1.2, s  # Morelli 2003 reports about 1.0 to 1.1 after optimisation
        assert np.max(np.abs(opt[s])) == pytest.approx(3 * DEG, rel=0.01)
        assert abs(opt[s][0]) < 1e-3 * 3 * DEG  # starts at zero


def test_harmonics_are_split_between_inputs_and_schroeder_flat_formula():
    k = harmonic_indices(0.1, 2.0, 20.0)
    assert k[0] == 2 and k[-1] == 40
    parts = split_harmonics(k, 3)
    assert sorted(np.concatenate(parts)) == list(k)
    assert all(len(set(a) & set(b)) == 0 for a in parts for b in parts if a is not b)
    # flat spectrum: phi_k = -pi k^2 / M up to a term linear in k (Schroeder 1970)
    m = 12
    ph = schroeder_phases(np.ones(m))
    kk = np.arange(1, m + 1)
    resid = ph - (-np.pi * kk**2 / m)
    assert np.allclose(np.diff(resid, 2), 0, atol=1e-12)
    c = Components(np.array([1.0]), np.array([1.0]), np.array([0.0]))
    assert relative_peak_factor(c(np.arange(1000) / 1000)) == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("rate_deg", [20.0, 60.0, 200.0])
def test_rate_limiting_never_exceeds_the_rate(rate_deg):
    t = np.arange(3000) / 100.0
    d = input_from_dict(
        {
            "kind": "3211",
            "surface": "de",
            "start": 2,
            "base": 1.0,
            "amplitude_deg": 5,
            "rate_limit_deg": rate_deg,
        }
    )
    u = d.signal(t)
    rates = np.abs(np.diff(u)) / np.diff(t)
    assert rates.max() <= rate_deg * DEG * (1 + 1e-12)
    assert rates.max() == pytest.approx(rate_deg * DEG, rel=1e-9)  # it is active
    assert np.max(u) == pytest.approx(5 * DEG)  # 1 s is long enough to reach the level
    # irregular time steps too
    tt = np.sort(np.random.default_rng(0).uniform(0, 30, 3000))
    y = rate_limit(tt, np.sin(3 * tt), 1.0)
    assert np.all(np.abs(np.diff(y)) <= np.diff(tt) * (1 + 1e-12))


def test_energy_spectrum_parseval_and_equal_energy_scaling():
    t = np.arange(4000) / 100.0
    d3211 = ThreeTwoOneOne(surface="de", start=5, base=0.7, amplitude=2 * DEG)
    doub = Doublet(surface="de", start=5, base=1.0, amplitude=2 * DEG)
    u = d3211.signal(t)
    f, p = spectrum(t, u)
    assert np.sum(p) * (f[1] - f[0]) == pytest.approx(energy(t, u), rel=1e-9)
    # a 3211 of base 0.7 s carries (3+2+1+1) * 0.7 * A^2 of energy
    assert energy(t, u) == pytest.approx(7 * 0.7 * (2 * DEG) ** 2, rel=1e-9)
    target = energy(t, u)
    scaled = scale_to_energy(doub, t, target)
    assert energy(t, scaled.signal(t)) == pytest.approx(target, rel=1e-6)
    # with a rate limit energy is not quadratic in amplitude; the secant refines it
    limited = Doublet(surface="de", start=5, base=0.3, amplitude=2 * DEG, rate_limit=60 * DEG)
    s2 = scale_to_energy(limited, t, target)
    assert energy(t, s2.signal(t)) == pytest.approx(target, rel=1e-5)
    # a rate limit of 10 deg/s caps a 0.3 s doublet far below the target: say so
    capped = Doublet(surface="de", start=5, base=0.3, amplitude=2 * DEG, rate_limit=10 * DEG)
    with pytest.raises(ValueError, match="cannot reach energy"):
        scale_to_energy(capped, t, target)
    # the doublet puts less energy at low frequency than the 3211 of equal energy
    f, p_d = spectrum(t, scaled.signal(t))
    low = f < 0.2
    assert np.sum(p[low]) > np.sum(p_d[low])


@pytest.mark.parametrize(
    "kind", ["pullup_pushover", "throttle_cut", "bank_to_bank", "figure_eight"]
)
def test_maneuvers_are_reproducible_trimmed_before_and_after(kind):
    t = np.arange(8000) / 100.0
    a = input_from_dict({"kind": kind, "start": 3, "seed": 7}).signals(t)
    b = input_from_dict({"kind": kind, "start": 3, "seed": 7}).signals(t)
    c = input_from_dict({"kind": kind, "start": 3, "seed": 8}).signals(t)
    d = input_from_dict({"kind": kind, "start": 3, "seed": 7})
    assert a.keys() == b.keys() == c.keys()
    for s in a:
        assert np.array_equal(a[s], b[s])
        assert not np.array_equal(a[s], c[s])
        assert np.all(a[s][t < 3 + d.lead] == 0)  # trimmed lead
        assert np.all(a[s][t > d.end - d.trail] == 0)  # trimmed trail
        assert np.any(a[s] != 0)


def test_pullup_pushover_follows_seed_003():
    t = np.arange(3000) / 100.0
    d = input_from_dict(
        {
            "kind": "pullup_pushover",
            "start": 0,
            "seed": 1,
            "timing_sigma": 0,
            "amplitude_sigma": 0,
            "tremor": 0,
        }
    )
    de = d.signal(t) if hasattr(d, "signal") else d.signals(t)["de"]
    assert de.min() == pytest.approx(-10 * DEG, abs=1e-9)  # -10 deg pull (Boomerang 60 paper)
    i = np.argmin(de)
    back = np.argmax(de[i:] >= -1e-12) + i
    assert t[back] - t[i] == pytest.approx(4.0, abs=0.011)  # released over 4 s


def test_throttle_cut_and_roll_signs():
    t = np.arange(6000) / 100.0
    s = input_from_dict(
        {"kind": "throttle_cut", "start": 0, "tremor": 0, "drop": 0.4, "amplitude_sigma": 0}
    ).signals(t)
    assert s["throttle"].min() == pytest.approx(-0.4)
    assert s["de"].min() < -10 * DEG  # nose-up elevator to hold altitude
    f8 = input_from_dict({"kind": "figure_eight", "start": 0, "tremor": 0, "seed": 2}).signals(t)
    first = f8["da"][np.nonzero(f8["da"])[0][0] + 5]
    assert first > 0  # left turn first: da > 0 rolls left (Cl_da < 0)
    assert np.all(np.sign(f8["dr"]) == np.sign(f8["da"]))  # coordinated rudder


def test_round_trip_and_sum_of_designs():
    t = np.arange(3000) / 100.0
    cards = [
        {"kind": "3211", "surface": "de", "start": 10, "base": 0.5, "amplitude_deg": 3},
        {
            "kind": "sweep",
            "surface": "da",
            "f_start": 0.2,
            "f_end": 2,
            "duration": 15,
            "amplitude_deg": 2,
            "law": "log",
        },
        {
            "kind": "multisine",
            "surface": "dr",
            "f_min": 0.2,
            "f_max": 1.5,
            "period": 10,
            "amplitude_deg": 2,
            "start": 1,
        },
        {
            "kind": "orthogonal_multisine",
            "surfaces": ["de", "da"],
            "amplitudes_deg": [1, 2],
            "period": 10,
            "f_max": 1.0,
        },
        {"kind": "step", "surface": "throttle", "amplitude": 0.1, "start": 20},
    ]
    designs = inputs_from_list(cards)
    for d in designs:
        again = input_from_dict(d.to_dict())
        assert again == d
        for s, u in d.signals(t).items():
            assert np.array_equal(u, again.signals(t)[s])
    total = total_signals(designs, t)
    assert set(total) == {"de", "da", "dr", "throttle"}
    assert np.allclose(total["de"], designs[0].signal(t) + designs[3].signals(t)["de"])
    assert set(INPUT_KINDS) >= {"doublet", "211", "3211", "sweep", "multisine", "figure_eight"}


@pytest.mark.parametrize(
    "card, field",
    [
        ({"surface": "de"}, "'kind'"),
        ({"kind": "4321"}, "'kind'"),
        ({"kind": "3211", "surface": "elevator"}, "'surface'"),
        ({"kind": "3211", "base": -1}, "'base'"),
        ({"kind": "3211", "base": "fast"}, "'base'"),
        ({"kind": "3211", "amplitud_deg": 3}, "'amplitud_deg'"),
        ({"kind": "3211", "amplitude": 0.1, "amplitude_deg": 3}, "'amplitude'"),
        ({"kind": "step", "surface": "throttle", "amplitude_deg": 3}, "'amplitude_deg'"),
        ({"kind": "3211", "base_deg": 3}, "'base_deg'"),
        ({"kind": "sweep", "law": "cubic"}, "'law'"),
        ({"kind": "sweep", "f_start": 0}, "'f_start'"),
        ({"kind": "sweep", "duration": 10, "fade_in": 6, "fade_out": 6}, "'fade_in'"),
        ({"kind": "multisine", "f_min": 2, "f_max": 1}, "'f_max'"),
        ({"kind": "multisine", "cycles": 1.5}, "'cycles'"),
        ({"kind": "orthogonal_multisine", "surfaces": ["de", "de"]}, "'surfaces'"),
        ({"kind": "orthogonal_multisine", "surfaces": ["de", "xx"]}, "'surfaces[1]'"),
        (
            {"kind": "orthogonal_multisine", "surfaces": ["de", "da"], "amplitudes": [1]},
            "'amplitudes'",
        ),
        (
            {
                "kind": "orthogonal_multisine",
                "surfaces": ["de", "da", "dr"],
                "f_min": 0.1,
                "f_max": 0.2,
                "period": 10,
            },
            "'period'",
        ),
        ({"kind": "bank_to_bank", "direction": "up"}, "'direction'"),
        ({"kind": "throttle_cut", "drop": 2}, "'drop'"),
    ],
)
def test_bad_dicts_name_the_field(card, field):
    with pytest.raises(ValueError, match=re.escape(field)):
        input_from_dict(card)


def test_bad_entry_in_a_list_is_located():
    with pytest.raises(ValueError, match=r"inputs\[1\]\.base"):
        inputs_from_list([{"kind": "doublet"}, {"kind": "doublet", "base": "x"}])
