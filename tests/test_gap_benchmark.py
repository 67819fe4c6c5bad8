"""The gap diagnosis's blind check (scenarios/gap_benchmark): a small fixed set of cases
flown, diagnosed without being told, and scored; the draw; the command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.scenarios.gap_benchmark import AIRCRAFT, Case, draw, run_case, summary
from flightid.scenarios.gap_benchmark.cases import DELTA_SCALE, STABLE_SIGN
from flightid.scenarios.gap_benchmark.run import truths
from flightid.scenarios.gap_benchmark.study import Benchmark

# the diagnosis with one step and no pairs: the test's cases are single effects, and the
# full search (pairs, three steps) is what the 50-case benchmark runs
FAST = {"try_pairs": False, "steps": 1}


@pytest.fixture(scope="module")
def results():
    cases = [
        Case(0, 11, "navion", "derivative_delta", {"derivative": "Cl_beta", "axes": "body"},
             {"delta": -0.025}),
        Case(1, 12, "twinotter", "control_effectiveness", {"surface": "dr"}, {"factor": 0.7}),
        Case(2, 13, "navion", "structural_mode", {},
             {"frequency_hz": 4.0, "damping": 0.03, "gain": 0.8}, in_catalogue=False),
        Case(3, 14, "twinotter", "vane_nonlinearity", {"channel": "beta"}, {"k": 7.0},
             in_catalogue=False),
    ]
    return [run_case(c, floor=False, **FAST) for c in cases]


def test_derivative_delta_attributed(results):
    r = results[0]
    assert r.top1 and r.top3 and not r.unexplained
    # measured: -0.0200 +- 0.0005 for the -0.025 flown (20 % short, 11 bounds): the gap
    # between the linearised model and JSBSim, not noise (docs/gap_benchmark.md); the
    # test holds the estimate to the right sign and within 30 % of the change
    assert r.estimate["delta"]["value"] < 0
    assert r.magnitude_error < 0.3
    assert r.shrink > 0.7


def test_control_effectiveness_attributed(results):
    r = results[1]
    assert r.top1, r.named
    assert r.magnitude_error < 0.2  # factor 0.7: within 0.06 of it
    assert r.shrink > 0.7


def test_small_gyro_scale_named():
    """A 16 % rate-gyro scale on the telemaster (case 44 of the seed-0 draw): held-out gain
    0.0037 of the measured energy, relative shrink 49 %. The absolute threshold of 0.005
    left it unexplained; at 0.002 (above the 0.0013 the linearisation's misfit gives on a
    null flight) it is named, within 2 % of the factor flown."""
    case = draw(50, 0, truths())[44]
    assert (case.aircraft, case.entry, case.options) == ("telemaster", "scale", {"channel": "r"})
    r = run_case(case, floor=False, **FAST)
    assert r.top1 and not r.unexplained, r.named
    assert r.magnitude_error < 0.02


def test_structural_mode_unexplained(results):
    r = results[2]
    assert not r.case.in_catalogue
    assert r.unexplained, f"a 4 Hz structural mode was named {r.named}"
    assert not r.top1 and not r.top3


def test_vane_nonlinearity_partly_unexplained(results):
    """A quadratic sideslip vane is mostly a beta scale at these sideslips: the closest
    catalogue entry is named, and the diagnosis says it leaves part of the gap above the
    noise floor (measured shares 0.21-0.46 on the blind check's vane cases, threshold 0.2;
    a right attribution, results[1], leaves 0.04 at most: docs/gap_benchmark.md)."""
    r = results[3]
    assert r.partly or r.unexplained, r.named
    assert not results[1].partly


def test_summary_fractions(results):
    s = summary(results)
    assert s["in_catalogue"] == 2 and s["outside"] == 2
    assert s["top1"] == 1.0 and s["unexplained_correct"] == 1.0
    assert s["false_unexplained"] == 0.0
    assert s["shrinkage"] > 0.7


def test_draw_is_fixed_by_seed_and_covers_the_aircraft():
    t = truths()
    a, b = draw(40, 3, t), draw(40, 3, t)
    assert [c.to_json() for c in a] == [c.to_json() for c in b]
    assert {c.aircraft for c in a} == set(AIRCRAFT)
    assert any(not c.in_catalogue for c in a) and any(c.in_catalogue for c in a)
    for c in a:
        if c.entry == "derivative_delta":  # moderate: at most half, at least 0.3 of a scale
            d = c.options["derivative"]
            assert abs(c.magnitude["delta"]) <= 0.5 * max(abs(t[c.aircraft][d]), 0.1) + 1e-12
        if c.entry in ("control_effectiveness",):
            assert 0.6 <= c.magnitude["factor"] <= 0.8
    assert draw(40, 4, t) != a


def test_draw_keeps_near_zero_stability_derivatives_stable():
    """A delta larger than half a near-zero derivative points the stable way: the
    telemaster's Cn_beta (-0.003) drawn -0.012 and -0.014 departed on the seeds 0 and 1."""
    t = truths()
    cases = [c for seed in range(6) for c in draw(50, seed, t)
             if c.entry == "derivative_delta" and c.options["derivative"] in STABLE_SIGN
             and abs(t[c.aircraft][c.options["derivative"]])
             < DELTA_SCALE[c.options["derivative"]]]
    assert cases  # the telemaster's Cn_beta is among them
    for c in cases:
        assert np.sign(c.magnitude["delta"]) == STABLE_SIGN[c.options["derivative"]], c.label


def test_command_rejects_bad_input():
    runner = CliRunner()
    r = runner.invoke(app, ["gap-benchmark", "--n", "0"])
    assert r.exit_code == 2 and "--n must be 1..10000, got 0" in r.output
    r = runner.invoke(app, ["gap-benchmark", "--format", "xml"])
    assert r.exit_code == 2 and "use one of table, json" in r.output


def test_json_shape(results, tmp_path):
    d = json.loads(json.dumps(Benchmark(4, 0, results).to_json()))
    for key in ("top1", "top3", "shrinkage", "unexplained_correct", "cases"):
        assert key in d
    assert len(d["cases"]) == 4
    assert d["cases"][2]["shrink"] is None or math.isfinite(d["cases"][2]["shrink"])
