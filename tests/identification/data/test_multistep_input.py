"""Multistep inputs as parameters (levels, sub-sample edges) and their use by output error.

The output-error cases fly the Navion lateral model (Teper 1969 via Nelson 1998, the
parameter set of ``test_output_error``) at 1 kHz with an aileron and a rudder doublet
whose command steps fall between the 25 Hz samples, through a servo that slews across
one sample interval (the transition that the parameterisation assumes for the sensor), and
record the surfaces with 0.2 deg of noise: the hobby recorder of the Telemaster (Sofyan,
RMIT thesis, c. 1997). A faster servo breaks that assumption: through a 10 ms first-order
lag instead, seeds 1-8 put the edges +4 ms late on average (+1.5 sigma) and Cl_beta, Cl_p
+4 % (+1 sigma).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from flightid.identification.data import multistep_input as ms
from flightid.identification.methods import output_error as oe
from flightid.identification.models import linear as lm
from flightid.identification.models.discrete import simulate
from flightid.identification.models.reference_condition import CONDITION_CHANNELS
from flightid.record import FlightRecord, RecordMeta, Reference
from tests.identification.methods.test_output_error import LATERAL_TRUTH, NAVION

DEG = np.pi / 180


@pytest.mark.parametrize("hold", ["foh", "zoh"])
def test_samples_hold_the_area_of_each_step_at_its_edge(hold):
    # the hold of the samples integrates to the ideal steps' integral, whatever the edges
    rng = np.random.default_rng(3)
    dt = 0.04
    t = np.arange(0, 4, dt)
    for _ in range(20):
        edges = tuple(np.sort(rng.uniform(0.5, 3.5, 3)))
        levels = tuple(rng.normal(size=4))
        u = ms.MultistepParameters(levels, edges).samples(t, hold)
        held = np.trapezoid(u, t) if hold == "foh" else np.sum(u[:-1]) * dt
        bounds = (t[0], *edges, t[-1])
        ideal = sum(a * (b1 - b0) for a, b0, b1 in zip(levels, bounds[:-1], bounds[1:],
                                                       strict=True))
        assert held == pytest.approx(ideal, abs=1e-12)


def test_sensitivities_are_the_derivatives_of_the_samples():
    t = np.arange(0, 2, 0.04)
    step = ms.MultistepParameters((0.1, 0.5, -0.3, 0.0), (0.513, 1.021, 1.537))
    d = step.sensitivities(t)
    values = step.parameters("da")
    for j, name in enumerate(step.parameter_names("da")):
        h = 1e-6
        up = step.with_parameters("da", {**values, name: values[name] + h}).samples(t)
        down = step.with_parameters("da", {**values, name: values[name] - h}).samples(t)
        np.testing.assert_allclose(d[:, j], (up - down) / (2 * h), atol=1e-6)


def test_a_step_exactly_on_the_grid_still_moves_one_sample():
    # one-sided derivative: an edge on a sample instant keeps a nonzero sensitivity
    t = np.arange(0, 1, 0.04)
    d = ms.MultistepParameters((0.0, 1.0), (0.5 - 0.02,)).sensitivities(t)  # arg exactly 1 at 0.48
    assert np.count_nonzero(d[:, -1]) == 1


def test_a_multistep_has_one_level_more_than_edges():
    with pytest.raises(ValueError, match="one level more than edges"):
        ms.MultistepParameters((0.0, 1.0), (0.5, 1.0))


def _servo(t: np.ndarray, commands: list[tuple[float, float]], slew: float) -> np.ndarray:
    """A surface (rad) following steps (time s, level rad), each a ramp of ``slew`` s."""
    out = np.zeros_like(t)
    for (t0, level), (_, before) in zip(commands, [(0.0, 0.0), *commands[:-1]], strict=True):
        out += (level - before) * np.clip((t - t0) / slew, 0.0, 1.0)
    return out


DOUBLETS = {"da": [(1.013, 2 * DEG), (1.527, -2 * DEG), (2.041, 0.0)],
            "dr": [(4.031, 1.5 * DEG), (4.518, -1.5 * DEG), (5.009, 0.0)]}
DAS, FINE = 25.0, 1000.0  # Hz
SLEW = 1 / DAS  # s: the area-equivalent edge is the command time + SLEW / 2
SURFACE_NOISE = 0.2 * DEG


def _flight(seed: int) -> tuple[FlightRecord, dict[str, float]]:
    truth = LATERAL_TRUTH["navion"]
    model = lm.lateral(NAVION)
    fine = np.arange(0, 8.0 + 0.5 / FINE, 1 / FINE)
    surfaces = {c: _servo(fine, cmd, SLEW) for c, cmd in DOUBLETS.items()}
    y = simulate(model, {**model.start, **truth}, fine,
                    np.column_stack([surfaces[c] for c in model.inputs]), hold="zoh")
    step = int(FINE / DAS)
    rng = np.random.default_rng(seed)
    noise = {"beta": 0.1 * DEG, "p": 0.2 * DEG, "r": 0.2 * DEG, "phi": 0.2 * DEG, "ay": 0.05}
    channels = {o: y[::step, j] + rng.normal(0, noise[o], y[::step].shape[0])
                for j, o in enumerate(model.outputs)}
    for c, x in surfaces.items():
        channels[c] = x[::step] + rng.normal(0, SURFACE_NOISE, x[::step].size)
    # the reference condition as constant channels, for ``flightid identify``
    channels.update({n: np.full(fine[::step].size, getattr(NAVION, n))
                     for n in CONDITION_CHANNELS})
    reference = Reference(NAVION.area, NAVION.span, NAVION.chord)
    record = FlightRecord(fine[::step], channels,
                          RecordMeta(sample_rate=DAS, reference=reference))
    edges = {f"edge_{c}_{k}": t0 + SLEW / 2 for c, cmd in DOUBLETS.items()
             for k, (t0, _) in enumerate(cmd)}
    return record, {**truth, **edges}


ROLL = ("Cl_beta", "Cl_p", "Cl_da", "Cn_r", "Cn_dr")


@pytest.fixture(scope="module", params=[1, 2, 3])
def fits(request):
    record, truth = _flight(request.param)
    model = lm.lateral(NAVION)
    plain = oe.estimate(record, model, colored=True)
    multistep = oe.estimate(record, model, colored=True, multistep_inputs=("da", "dr"))
    return plain, multistep, truth


def test_multistep_estimates_within_3_sigma_of_truth(fits):
    # seeds 1-8: |z| <= 2.7 for the derivatives, 1.8 for the edges; with the raw surfaces
    # as exact inputs Cl_beta reads -25 % (+3.5 sigma) on seed 1
    _, est, truth = fits
    assert est.fit["converged"]
    edges = [n for n in truth if n.startswith("edge_")]
    assert set(edges) <= set(est.names)  # every step found
    bad = {n: f"{(est[n] - truth[n]) / est.std_of(n):+.2f} sigma" for n in (*ROLL, *edges)
           if abs(est[n] - truth[n]) >= 3 * est.std_of(n)}
    assert not bad, bad


def test_edges_found_between_the_samples(fits):
    # on the 25 Hz grid alone a step is up to 20 ms off (rms 11.5 ms); the edge bounds are
    # 1.5-5 ms (rms about 3.5 ms), measured rms error 2-5 ms over seeds 1-8
    _, est, truth = fits
    errors = np.array([est[n] - truth[n] for n in truth if n.startswith("edge_")])
    assert np.sqrt(np.mean(errors**2)) < 0.006


def test_from_measurement_places_noise_free_edges_exactly():
    # a ramp of one sample interval is sampled exactly as the FOH image: the area of the
    # samples next to each step gives its edge, one transition sample per step joined
    t = np.arange(0, 3, 1 / DAS)
    commands = [(0.513, 1.0), (1.027, -1.0), (1.541, 0.0)]
    y = _servo(t, commands, SLEW)
    step = ms.from_measurement(t, y)
    np.testing.assert_allclose(step.edges, [c + SLEW / 2 for c, _ in commands], atol=1e-9)
    np.testing.assert_allclose(step.levels, [0.0, 1.0, -1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(step.samples(t), y, atol=1e-9)


def test_surfaces_are_outputs_of_the_multistep_fit(fits):
    _, est, _ = fits
    assert {"da", "dr"} <= set(est.outputs)
    assert est.fit["noise_std"]["da"] == pytest.approx(SURFACE_NOISE, rel=0.25)


def test_a_multistep_input_must_be_a_model_input():
    record, _ = _flight(1)
    with pytest.raises(ValueError, match="de not input"):
        oe.estimate(record, lm.lateral(NAVION), multistep_inputs=("de",))


def test_identify_cli_estimates_the_multisteps_by_output_error(tmp_path):
    record, truth = _flight(1)
    path = record.write(tmp_path / "navion_doublets.parquet")
    out = subprocess.run(
        [sys.executable, "-m", "flightid.cli.app", "identify", str(path), "--method", "oe",
         "--model", "lateral", "--multistep-input", "da", "--multistep-input", "dr",
         "--option", "colored=true", "--format", "json"],
        capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    est = json.loads(out.stdout)["estimates"]
    for name in ("edge_da_0", "edge_dr_2", "Cl_da"):
        assert abs(est[name]["value"] - truth[name]) < 3 * est[name]["std"]
