"""Scoring against truth, the identify front door and the `flightid identify` command."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flightid.cli.app import app
from flightid.cli.tables import print_score
from flightid.identification.estimate import Estimate, StdKind
from flightid.identification.evaluation.scoring import load_truth, score
from flightid.identification.identify import identify
from flightid.identification.methods.registry import methods
from flightid.identification.models.structure import regression
from tests.conftest import TWIN_OTTER

# output-error values of the README (Morelli & Klein example 6.1) as an independent truth
OE_TRUTH = {"Cn_beta": 0.08638, "Cn_p": -0.06441, "Cn_r": -0.19059, "Cn_da": -0.00298,
            "Cn_dr": -0.13548}


def _estimate() -> Estimate:
    return Estimate("test", ["Cm_alpha", "Cm_q", "Cm_0"], np.array([-1.2, -30.0, 0.01]),
                    np.array([0.05, 2.0, 0.001]),
                    unidentifiable={"Cm_de": "de is constant (std 0.0 rad) in this record"})


def test_rows_verdict_and_unidentifiable():
    truth = {"Cm_alpha": -1.3, "Cm_q": -34.0, "Cm_de": -1.7, "CL_alpha": 5.7, "Cm_0": 0.0}
    s = score(_estimate(), truth, scope="all")
    rows = {r.name: r for r in s.rows}
    assert rows["Cm_alpha"].error == pytest.approx(0.1)
    assert rows["Cm_alpha"].sigmas == pytest.approx(2.0)
    assert rows["Cm_q"].sigmas == pytest.approx(2.0)
    assert rows["Cm_de"].status == "unidentifiable" and rows["Cm_de"].estimate is None
    assert rows["CL_alpha"].status == "not estimated"
    assert "Cm_0" not in rows  # a coefficient at the reference condition is not scored
    assert s.verdict == ("2 estimated, 2 within 3 sigma, worst Cm_alpha at 2.0 sigma; "
                         "1 unidentifiable (Cm_de); 1 not estimated (CL_alpha)")
    d = json.loads(s.to_json())
    assert d["rows"][2]["estimate"] is None and "constant" in d["rows"][2]["reason"]
    # by default only what the estimate covers: estimated and unidentifiable
    assert [r.name for r in score(_estimate(), truth).rows] == ["Cm_alpha", "Cm_q", "Cm_de"]


def test_an_infinite_sigma_is_null_in_strict_json():
    # a zero standard error and a non-zero error: infinitely many sigmas
    est = Estimate("test", ["Cm_alpha"], np.array([-1.2]), np.array([0.0]))
    row = score(est, {"Cm_alpha": -1.3}).rows[0]
    assert row.sigmas == float("inf")
    d = json.loads(json.dumps(score(est, {"Cm_alpha": -1.3}).as_dict(), allow_nan=False))
    assert d["rows"][0]["sigmas"] is None and d["rows"][0]["error"] == pytest.approx(0.1)


def test_table_prints_unidentifiable_as_text():
    from rich.console import Console

    console = Console(record=True, width=160)
    print_score(score(_estimate(), {"Cm_alpha": -1.3, "Cm_de": -1.7}), console)
    text = console.export_text()
    assert "unidentifiable: de is constant" in text and "-1.7" in text


def test_load_truth_forms_and_errors(tmp_path):
    good = tmp_path / "t.json"
    good.write_text(json.dumps({"truth": {"Cm_q": {"value": -34}, "Cm_alpha": -1.3}}))
    assert load_truth(good) == {"Cm_q": -34.0, "Cm_alpha": -1.3}
    bad = tmp_path / "bad.json"
    bad.write_text('{"Cm_q": -34,\n "Cm_alpha": }')
    with pytest.raises(ValueError, match="line 2"):
        load_truth(bad)
    bad.write_text('{"Cm_q": "big"}')
    with pytest.raises(ValueError, match="field 'Cm_q'"):
        load_truth(bad)


def test_models_and_methods():
    assert set(methods()) >= {"ee", "swr"}
    assert regression("Cn=beta+rhat; CY=beta")["Cn"] == ["beta", "rhat"]
    with pytest.raises(ValueError, match="unknown model"):
        regression("sideways")
    from flightid.sidpac import read_mat

    rec = read_mat(TWIN_OTTER)
    est = identify(rec, "ee", "lateral", coefficients=["Cn"], colored=False)
    assert est.names[0].startswith("Cn_") and est["Cn_dr"] == pytest.approx(-0.13054, rel=0.01)
    with pytest.raises(ValueError, match="unknown method"):
        identify(rec, "magic")
    with pytest.raises(ValueError, match="unknown option.*f_in.*valid: coefficients"):
        identify(rec, "ee", "lateral", f_in=4)


def test_cli_identify_json_and_score(tmp_path):
    truth = tmp_path / "truth.json"
    truth.write_text(json.dumps(OE_TRUTH))
    result = CliRunner().invoke(app, ["identify", str(TWIN_OTTER), "--method", "ee",
                                      "--coefficient", "Cn", "--truth", str(truth),
                                      "--format", "json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["estimates"]["Cn_beta"]["value"] == pytest.approx(0.08544, rel=0.01)
    assert out["std_kind"] == StdKind.CRAMER_RAO_COLORED == "cramer-rao-colored"
    # equation error vs output error on real data: Cn_p and Cn_da differ by more than
    # 3 corrected bounds (the README's point about methods disagreeing on real data)
    rows = {r["name"]: r for r in out["score"]["rows"]}
    assert abs(rows["Cn_beta"]["sigmas"]) < 3.0
    assert abs(rows["Cn_da"]["sigmas"]) > 3.0
    table = CliRunner().invoke(app, ["identify", str(TWIN_OTTER), "--method", "swr",
                                     "--coefficient", "CY"])
    assert table.exit_code == 0, table.output
    assert "CY_beta" in table.output and "enter" in table.output
