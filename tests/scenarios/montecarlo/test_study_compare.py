"""flightid study-compare: two studies side by side, each derivative's scatter ratio to
the first with its interval, and the mean scatter / |truth| ratio with its paired
interval; studies written through the study store with fixed-seed errors of known
scatter."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.study import Study

RUNNER = CliRunner()
TRUTH = {"Cl_p": -0.41, "Cn_r": -0.125}


def _study(folder, scale: float, n: int = 40) -> None:
    store.open_study(folder, Study(card="navion-demo", n=n, seed=1))
    rng = np.random.default_rng(11)  # the same draws in both: errors correlated 1
    for i in range(n):
        z = rng.normal(size=len(TRUTH))
        rows = [{"index": i, "seed": i, "name": name, "truth": t,
                 "estimate": t + scale * 0.01 * zi, "std": scale * 0.01,
                 "error": scale * 0.01 * zi, "sigmas": zi, "status": "estimated",
                 "reason": ""} for (name, t), zi in zip(TRUTH.items(), z, strict=True)]
        store.write_realization(folder, i, rows)


def test_study_compare_gives_the_ratio_to_the_first_study_with_intervals(tmp_path):
    _study(tmp_path / "base", 1.0)
    _study(tmp_path / "half", 0.5)
    result = RUNNER.invoke(app, ["study-compare", str(tmp_path / "base"),
                                 str(tmp_path / "half"), "--format", "json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["names"] == ["base", "half"]
    versus = data["against_first"]["half"]
    for name in TRUTH:
        r = versus["ratios"][name]
        # errors exactly half of the first study's, realization by realization
        assert r["ratio"] == pytest.approx(0.5, rel=1e-9)
        assert r["interval"] == "paired" and r["winner"] == "half"
        assert r["low"] == pytest.approx(0.5, rel=1e-9)
    m = versus["mean_relative_scatter"]
    assert m["ratio"] == pytest.approx(0.5, rel=1e-9) and m["realizations"] == 40
    table = RUNNER.invoke(app, ["study-compare", str(tmp_path / "base"),
                                str(tmp_path / "half")], env={"COLUMNS": "80"})
    assert table.exit_code == 0
    assert max(len(line) for line in table.stdout.splitlines()) <= 80
    assert "0.500 times base's" in table.stdout


def test_study_compare_refuses_a_folder_without_a_study(tmp_path):
    _study(tmp_path / "base", 1.0, n=3)
    (tmp_path / "empty").mkdir()
    result = RUNNER.invoke(app, ["study-compare", str(tmp_path / "base"),
                                 str(tmp_path / "empty")])
    assert result.exit_code == 2
    assert "not a Monte Carlo study" in result.output
