"""A study's tables for a paper: summary.md and summary.tex beside summary.csv, with every
derivative and its numbers to four significant digits."""

from __future__ import annotations

import numpy as np

from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.report import write_report
from flightid.scenarios.montecarlo.summary import summarize


def test_the_report_writes_the_summary_as_markdown_and_latex(tmp_path):
    rng = np.random.default_rng(3)
    rows = []
    for i in range(8):
        for name, truth, s in (("Cl_p", -0.41, 0.02), ("CY_r", 0.0, 0.1)):
            e = float(rng.normal() * s)
            rows.append({"index": i, "seed": i, "name": name, "truth": truth,
                         "estimate": truth + e, "std": s, "error": e, "sigmas": e / s,
                         "status": "estimated", "reason": ""})
    df = store.frame(rows)
    summary = summarize(df)
    write_report(tmp_path, df, summary)
    md = (tmp_path / "summary.md").read_text()
    tex = (tmp_path / "summary.tex").read_text()
    scatter = {r.name: r.scatter for r in summary.rows}
    for name in ("Cl_p", "CY_r"):
        assert f"| {name} |" in md
        assert f"{scatter[name]:.4g}" in md and f"{scatter[name]:.4g}" in tex
    assert "Cl\\_p" in tex and "\\toprule" in tex
    assert md.count("\n") == 2 + len(summary.rows)  # header, rule, one line per derivative
