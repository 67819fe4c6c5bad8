"""Frequency responses: Fourier integral accuracy, random error, coherence, conditioning."""

import numpy as np
import pytest
from scipy import signal

from flightid.identification.frequency.fourier import finite_fourier_transform
from flightid.identification.frequency.response import (
    FrequencyResponse,
    composite,
    estimate_response,
    frequency_response,
    frequency_response_arrays,
)
from flightid.identification.frequency.spectra import cross_spectra
from flightid.record import FlightRecord

DT = 0.02
WN, ZETA, TAU = 6.0, 0.4, 0.1  # rad/s, -, s


def true_response(f: np.ndarray) -> np.ndarray:
    s = 2j * np.pi * f
    return WN**2 / (s**2 + 2 * ZETA * WN * s + WN**2) * np.exp(-s * TAU)


def simulate(u: np.ndarray, t: np.ndarray) -> np.ndarray:
    sys = signal.lti([WN**2], [1, 2 * ZETA * WN, WN**2])
    _, y, _ = signal.lsim(sys, np.interp(t - TAU, t, u, left=0.0), t)
    return y


def test_fourier_integral_is_exact_for_smooth_signals():
    # int_0^T e^{-0.3t} sin(1.3t) e^{-jwt} dt in closed form; the cubic Filon corrections
    # make the 50 Hz sum accurate to ~1e-8, the plain Euler sum only to ~1e-4.
    t = np.arange(0, 20 + 1e-9, DT)
    a, c = 1.3, 0.3
    x = np.exp(-c * t) * np.sin(a * t)
    for f in (np.linspace(0.1, 1.5, 71), np.geomspace(0.05, 10.0, 40)):
        b = c + 2j * np.pi * f

        def antiderivative(tt, b=b):
            return np.exp(-b * tt) * (-b * np.sin(a * tt) - a * np.cos(a * tt)) / (a**2 + b**2)

        exact = antiderivative(t[-1]) - antiderivative(0.0)
        corrected = finite_fourier_transform(x, DT, f)
        plain = finite_fourier_transform(x, DT, f, correct=False)
        assert np.max(np.abs(corrected - exact)) < 1e-7
        assert np.max(np.abs(plain - exact)) > 1e-5
    with pytest.raises(ValueError, match="Nyquist"):
        finite_fourier_transform(x, DT, np.array([30.0]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_error_predicts_the_scatter_of_the_response(seed):
    # Band-limited random input, output noise 30 % of the output rms. For the H1 estimate
    # the error of |H| / |H_true| - 1 and of the phase (rad) has standard deviation eps_r
    # (Bendat & Piersol eq. 9.90), so the normalised errors have rms ~ 1; 40 correlated
    # points: none beyond 5.
    rng = np.random.default_rng(seed)
    t = np.arange(0, 200, DT)
    b, a = signal.butter(4, 4.0, fs=1 / DT)
    u = signal.lfilter(b, a, rng.standard_normal(t.size))
    y = simulate(u, t)
    y = y + 0.3 * np.std(y) * rng.standard_normal(t.size)
    f = np.geomspace(0.2, 3.0, 40)
    for windows in ((20.0,), None):
        r = frequency_response_arrays({"u": u}, y, DT, frequencies=f, windows=windows)["u"]
        ratio = r.response / true_response(f)
        mag = (np.abs(ratio) - 1) / r.random_error
        ph = np.angle(ratio) / r.random_error
        for e in (mag, ph):
            assert 0.6 < np.sqrt(np.mean(e**2)) < 1.6
            assert np.max(np.abs(e)) < 5.0


def sweep(t: np.ndarray) -> np.ndarray:
    return signal.chirp(t, 0.05, t[-1], 4.0, method="logarithmic") * np.minimum(1.0, t / 3.0)


def test_sweep_response_matches_the_known_transfer_function():
    # Log sweep 0.05-4 Hz, 90 s, 10 % output noise. Magnitude within 3 eps_r plus the
    # leakage bias of windowing a sweep (measured noise-free: <= 4 % below 2 Hz).
    rng = np.random.default_rng(7)
    t = np.arange(0, 90, DT)
    u = sweep(t)
    y = simulate(u, t)
    y = y + 0.1 * np.std(y) * rng.standard_normal(t.size)
    f = np.geomspace(0.1, 2.0, 50)
    r = frequency_response_arrays({"u": u}, y, DT, frequencies=f)["u"]
    ratio = r.response / true_response(f)
    assert np.all(r.coherence > 0.9)
    assert np.all(np.abs(np.abs(ratio) - 1) < 3 * r.random_error + 0.04)
    assert np.all(np.abs(np.angle(ratio)) < 3 * r.random_error + 0.04)


def test_coherence_drops_where_band_limited_noise_dominates():
    rng = np.random.default_rng(3)
    t = np.arange(0, 90, DT)
    u = sweep(t)
    y0 = simulate(u, t)
    b, a = signal.butter(4, [0.8, 1.2], btype="band", fs=1 / DT)
    noise = signal.filtfilt(b, a, rng.standard_normal(t.size))
    noise *= 2.0 * np.std(y0) / np.std(noise)
    y = y0 + noise + 0.02 * np.std(y0) * rng.standard_normal(t.size)
    r = frequency_response_arrays({"u": u}, y, DT, frequencies=np.geomspace(0.1, 3.0, 60))["u"]
    f = r.frequency
    in_band = (f > 0.85) & (f < 1.15)
    clean = (f < 0.65) | ((f > 1.45) & (f < 2.5))
    assert in_band.sum() >= 5 and clean.sum() >= 30
    assert np.all(r.coherence[in_band] < 0.6)
    assert np.all(r.coherence[clean] > 0.9)
    # the random error follows: large in the noisy band, small outside
    assert np.min(r.random_error[in_band]) > 5 * np.max(r.random_error[clean])


def test_conditioning_separates_correlated_inputs():
    # y = G1 u1 + G2 u2 with u2 partly a low-passed copy of u1 (correlated inputs, as with
    # a pilot's off-axis corrections). The SISO estimate y/u1 is biased by the u2 path;
    # the conditioned (MISO) estimate recovers G1 and G2. Tolerance: 4 eps_r plus the
    # leakage bias of 100 s / 50 s windows, measured noise-free on this system (<= 5 %
    # where the u2 path carries a tenth or more of the output, 0.3-2 Hz).
    rng = np.random.default_rng(11)
    t = np.arange(0, 400, DT)
    b, a = signal.butter(3, 3.0, fs=1 / DT)
    u1 = signal.lfilter(b, a, rng.standard_normal(t.size))
    own = signal.lfilter(b, a, rng.standard_normal(t.size))
    u2 = 0.8 * signal.lfilter(*signal.butter(2, 0.8, fs=1 / DT), u1) + 0.6 * own
    g1 = signal.lti([4.0], [1.0, 2.0])
    g2 = signal.lti([-2.0, 0.0], [1.0, 1.5, 9.0])
    y = signal.lsim(g1, u1, t)[1] + signal.lsim(g2, u2, t)[1]
    y = y + 0.05 * np.std(y) * rng.standard_normal(t.size)
    f = np.geomspace(0.3, 2.0, 25)
    miso = frequency_response_arrays({"u1": u1, "u2": u2}, y, DT, frequencies=f,
                                     windows=(100.0, 50.0))
    siso = frequency_response_arrays({"u1": u1}, y, DT, frequencies=f,
                                     windows=(100.0, 50.0))["u1"]
    s = 2j * np.pi * f
    h1 = 4.0 / (s + 2.0)
    h2 = -2.0 * s / (s**2 + 1.5 * s + 9.0)
    for name, truth in (("u1", h1), ("u2", h2)):
        r = miso[name]
        assert r.conditioned_on == ({"u1": "u2", "u2": "u1"}[name],)
        err = np.abs(r.response / truth - 1)
        assert np.all(err < 4 * r.random_error + 0.05), (name, err.max())
        assert np.all(r.multiple_coherence > 0.95)
    assert np.max(np.abs(siso.response / h1 - 1)) > 0.2  # the unconditioned one is wrong


def test_composite_weights_windows_by_their_random_error():
    f = np.array([1.0, 2.0])
    a = FrequencyResponse(f, np.array([1.0, 1.0]), np.array([0.9, 0.9]), np.array([0.1, 0.1]))
    b = FrequencyResponse(f, np.array([2.0, 2.0]), np.array([0.5, 0.9]),
                          np.array([0.2, np.inf]))
    c = composite([a, b])
    # weights 1/0.01 and 1/0.04 -> (100*1 + 25*2)/125 = 1.2; second point: only window a
    assert c.response == pytest.approx([1.2, 1.0])
    assert c.random_error == pytest.approx([(100 * 0.1 + 25 * 0.2) / 125, 0.1])
    assert c.coherence == pytest.approx([(100 * 0.9 + 25 * 0.5) / 125, 0.9])


def test_spectra_scale_and_bad_input():
    # white noise of variance s2 sampled at dt has one-sided PSD 2 s2 dt
    rng = np.random.default_rng(5)
    x = 2.0 * rng.standard_normal(60000)
    sp = cross_spectra(x, DT, 10.0, np.linspace(1.0, 20.0, 50))
    assert np.mean(sp.matrix[:, 0, 0].real) == pytest.approx(2 * 4.0 * DT, rel=0.03)
    with pytest.raises(ValueError, match="longer than the record"):
        cross_spectra(x[:100], DT, 10.0, np.array([1.0]))
    with pytest.raises(ValueError, match="not finite at sample 3"):
        bad = x[:1000].copy()
        bad[3] = np.nan
        cross_spectra(bad, DT, 5.0, np.array([1.0]))
    with pytest.raises(ValueError, match="unknown taper"):
        estimate_response({"u": x}, x, DT, window=5.0, frequencies=np.array([1.0]),
                          taper="kaiser")


def test_record_interface_names_input_and_output():
    t = np.arange(0, 60, DT)
    u = sweep(t)
    rec = FlightRecord(t, {"de": u, "q": simulate(u, t)})
    r = frequency_response(rec, "de", "q", frequencies=np.geomspace(0.2, 2.0, 20))
    assert (r.input, r.output) == ("de", "q")
    assert np.all(np.abs(np.abs(r.response / true_response(r.frequency)) - 1) < 0.05)
    with pytest.raises(KeyError, match="no channel 'dr'"):
        frequency_response(rec, "dr", "q")
