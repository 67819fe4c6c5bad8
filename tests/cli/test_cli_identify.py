"""The command-line chain a flight-test engineer uses: simulate, truth, identify, report."""

import json
import os
import re
import subprocess
import sys

import pytest

from flightid.record import read
from tests.conftest import TWIN_OTTER

CLI = [sys.executable, "-m", "flightid.cli.app"]


def _run(*args: str) -> subprocess.CompletedProcess:
    out = subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return out


@pytest.mark.parametrize("seed", ["3"])
def test_simulate_truth_identify_chain_scores_within_3_sigma(tmp_path, seed):
    flight = tmp_path / "flight.parquet"
    # navion-demo: light turbulence, calibrated research sensors; the lateral window only
    _run("simulate", "navion-demo", "-o", str(flight), "--seed", seed)
    lateral = tmp_path / "lateral.parquet"
    read(flight).slice(13.0, 45.0).write(lateral)
    truth = tmp_path / "truth.json"
    truth.write_text(_run("truth", "navion", "--altitude", "0", "--speed", "53.64",
                          "--axes", "body", "--format", "json").stdout)
    report = tmp_path / "report.html"
    out = _run("identify", str(lateral), "--method", "oe", "--model", "lat", "--truth",
               str(truth), "--format", "json", "--report", str(report),
               "--option", "colored=true", "--option", "initial_state=estimate")
    result = json.loads(out.stdout)
    rows = {r["name"]: r for r in result["score"]["rows"] if r["status"] == "estimated"}
    assert {"Cl_p", "Cn_r", "Cn_beta", "Cl_da", "Cn_dr"} <= set(rows)
    for name in ("Cl_p", "Cn_r", "Cn_beta", "Cl_da", "Cn_dr"):
        assert abs(rows[name]["sigmas"]) < 3, rows[name]
    html = report.read_text()
    assert "output error" in html and html.count("data:image/png;base64,") >= 2


def test_identify_twin_otter_report(tmp_path):
    report = tmp_path / "totter.html"
    out = _run("identify", str(TWIN_OTTER), "--method", "ee", "--model", "lateral",
               "--report", str(report))
    assert "Cn_beta" in out.stdout
    html = report.read_text()
    # one estimate (CY, Cl, Cn merged): its table, the fit of each coefficient plotted
    assert html.count("<table>") >= 1 and html.count("<img") >= 2



def test_identify_with_multistep_inputs_and_a_missing_one(tmp_path):
    out = _run("identify", str(TWIN_OTTER), "--method", "ee", "--model", "lateral",
               "--multistep-input", "da", "--multistep-input", "dr", "--format", "json")
    assert "Cn_dr" in json.loads(out.stdout)["estimates"]
    bad = subprocess.run([*CLI, "identify", str(TWIN_OTTER), "--multistep-input", "dz"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode != 0
    assert "multistep input(s) dz not" in bad.stderr


def test_identify_tables_keep_every_digit_at_80_columns_through_a_pipe(tmp_path):
    """identify's estimate and score tables in an 80-column terminal, piped: no line wider,
    no cell cut with an ellipsis, every value, std and truth of the JSON output whole."""
    flight, truth = tmp_path / "flight.parquet", tmp_path / "truth.json"
    _run("simulate", "navion-demo", "-o", str(flight), "--seed", "3")
    truth.write_text(_run("truth", "navion", "--altitude", "0", "--speed", "53.64",
                          "--axes", "body", "--format", "json").stdout)
    args = ["identify", str(flight), "--method", "ee", "--model", "lat", "--truth", str(truth)]
    doc = json.loads(_run(*args, "--format", "json").stdout)
    out = subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "COLUMNS": "80"})
    assert out.returncode == 0, out.stderr
    text = out.stdout
    assert "…" not in text and max(len(line) for line in text.splitlines()) <= 80
    cells = {c.strip() for line in text.splitlines() for c in re.split("[│┃]", line)}
    for name, e in doc["estimates"].items():
        assert f"{e['value']:.5g}" in cells and f"{e['std']:.3g}" in cells, name
    for r in doc["score"]["rows"]:
        if r["status"] == "estimated":
            assert {f"{r['truth']:.5g}", f"{r['error']:+.3g}", f"{r['sigmas']:+.2f}"} <= cells
