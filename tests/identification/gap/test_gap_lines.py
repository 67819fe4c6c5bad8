"""The spectral-line check of the gap diagnosis (identification/gap/lines.py): engine
vibration named from a narrowband line on the IMU channels, a null flight and a
structural mode not.

JSBSim flights of the blind check's card (``scenarios.gap_benchmark.run``: 64 s at 50 Hz,
research sensors with 4-pole 10 Hz anti-alias filters, light turbulence) on seeds the
development of the thresholds did not use (it flew seeds 0 and 10). The c172p's engine
turns at 2090-2150 rpm (35 Hz), above the 25 Hz Nyquist frequency: its line shows at the
alias |f - 50 Hz| near 14.6 Hz."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from flightid.identification.gap import diagnose
from flightid.identification.gap.lines import RESONANCE, spectral_line, without_line
from flightid.scenarios.cards import fly_card
from flightid.scenarios.gap_benchmark.cases import NULL, NULL_INDEX, SINGLE, Case, Effect
from flightid.scenarios.gap_benchmark.outside_catalogue import structural_mode
from flightid.scenarios.gap_benchmark.run import card, fly_case
from flightid.scenarios.gap_benchmark.scoring import score

RATE = 50.0
# the injected amplitudes: half the blind check's smallest c172p draw (m/s^2, rad/s)
VIBRATION = {"ax": 2.0, "ay": 2.0, "az": 3.0, "p": 0.035, "q": 0.035, "r": 0.0175}
BIN_HZ = 1 / 5.12  # the check's segments: 256 samples at 50 Hz


@pytest.fixture(scope="module")
def vibrated():
    """(measured, truth) of a c172p flight with the engine vibration on the IMU."""
    return fly_card(card("c172p", 43, disturbances=[
        {"kind": "engine_vibration", **VIBRATION}]))


def _alias(f: np.ndarray) -> np.ndarray:
    return np.abs(f - np.round(f / RATE) * RATE)


def test_engine_line_named_at_its_alias_with_its_filtered_amplitude(vibrated):
    measured, truth = vibrated
    for axis in ("lateral", "longitudinal"):
        line = spectral_line([measured], axis)
        assert line is not None and line.named, line
        # the rotation line at its alias: the rpm drifts 2.5 % with the airspeed over the
        # maneuvers, so the segments' median peak lies within two bins of the median alias
        rotation = truth["rpm"] / 60.0
        assert abs(line.frequency_hz - float(np.median(_alias(rotation)))) <= 2 * BIN_HZ
        assert any(abs(a - float(np.median(rotation))) < 2 * BIN_HZ for a in line.aliases())
        # the amplitude as seen: the injected one through the 4-pole Butterworth at the
        # true frequency; within 25 %: the Hann window's scallop loss (up to 15 %) and the
        # line's drift within a segment spread it
        b, a = signal.butter(4, 2 * np.pi * 10.0, analog=True)
        _, h = signal.freqs(b, a, worN=[2 * np.pi * float(np.median(rotation))])
        for ch, amp in line.amplitudes.items():
            assert amp == pytest.approx(VIBRATION[ch] * abs(h[0]), rel=0.25), ch
        # the catalogue's amplitude, before the filter, at the alias that is the engine's
        (at,) = [f for f in line.before_filter if abs(f - np.median(rotation)) < 2 * BIN_HZ]
        for ch, amp in line.before_filter[at].items():
            assert amp == pytest.approx(VIBRATION[ch], rel=0.25), ch


def test_a_named_line_taken_out_leaves_the_rigid_body_band(vibrated):
    measured, _ = vibrated
    line = spectral_line([measured], "longitudinal")
    (clean,) = without_line([measured], line)
    assert not spectral_line([clean], "longitudinal").named
    assert not spectral_line([clean], "lateral").named
    # below 2 Hz the band-stop (13-16 Hz) passes the signal: its power gain there is
    # 1 - 1e-11 (docstring); the zero-phase filter's end transients stay within 1e-3
    low = signal.butter(4, 2.0, fs=RATE, output="sos")
    for ch in ("az", "q", "p"):
        a, b = (signal.sosfiltfilt(low, r[ch]) for r in (measured, clean))
        assert np.std(a - b) < 1e-3 * np.std(a), ch


def test_engine_vibration_named_in_the_diagnosis_and_scored_right():
    effect = Effect("engine_vibration", "both", "disturbance", {}, VIBRATION)
    case = Case(0, 43, "c172p", SINGLE, (effect,))
    result = diagnose([fly_case(case)], "c172p", try_pairs=False, steps=1)
    for axis, g in result.axes().items():
        assert g.line is not None and g.line.named, axis
        assert g.verdict != "no_gap"
        assert g.axis_json()["line"]["entry"] == "engine_vibration"
    scored = score(case, result)
    assert scored.right is True
    assert all("engine_vibration()" in n for n in scored.named.values())


@pytest.fixture(scope="module")
def null_record():
    return fly_case(Case(NULL_INDEX, 44, "c172p", NULL))


def test_null_flight_names_no_line(null_record):
    for axis in ("lateral", "longitudinal"):
        line = spectral_line([null_record], axis)
        # the development's 200 null flights: a peak near a common frequency in at most 2
        # of 24 segments per axis
        assert line is not None and not line.named and not line.resonance
        assert line.found < RESONANCE


@pytest.mark.parametrize(("axis", "frequency_hz", "rung"),
                         [("lateral", 5.5, True), ("longitudinal", 4.4, False)])
def test_structural_mode_is_not_named_engine_vibration(null_record, axis, frequency_hz, rung):
    # the blind check's structural mode: light damping, ringing after each surface step.
    # Laterally it rings after the aileron and rudder steps (4 maneuvers over 40 s): found
    # near 5.5 Hz in about half the segments, a resonance; the elevator's two maneuvers in
    # the last 22 s ring in fewer segments than the resonance needs
    record = structural_mode(null_record, frequency_hz, 0.03, 0.9, axis=axis)
    line = spectral_line([record], axis)
    assert line is not None and not line.named
    assert line.resonance is rung
    if rung:
        assert abs(line.frequency_hz - frequency_hz) <= 2 * BIN_HZ


def test_structural_resonance_leaves_its_axis_unexplained(null_record):
    # the lateral mode of the test above, diagnosed: not named, and not "no gap"
    record = structural_mode(null_record, 5.5, 0.03, 0.9, axis="lateral")
    g = diagnose([record], "c172p", try_pairs=False, steps=1).axes()["lateral"]
    assert g.line is not None and g.line.resonance
    assert g.verdict in ("unexplained", "partly_unexplained")
    assert "engine_vibration" not in {r.candidate.entry for r in g.named}
