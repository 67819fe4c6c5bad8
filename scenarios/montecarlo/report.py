"""STUDY/report.html: the summary table and, per derivative, a histogram of the
estimates with the truth and the normal curve the mean reported bound predicts (centred
on the truth); figures drawn with ``matplotlib.figure.Figure`` and embedded as base64
PNG, so the file stands alone."""

from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from flightid.identification.scoring import STATUS_ESTIMATED
from flightid.scenarios.montecarlo.summary import Summary

REPORT = "report.html"


def _figure(name: str, values: np.ndarray, truth: float, bound: float) -> str:
    # fixed margins: a constrained layout draws every figure twice (half the report's time)
    fig = Figure(figsize=(4.2, 2.8), dpi=100)
    fig.subplots_adjust(left=0.13, right=0.97, bottom=0.12, top=0.9)
    ax = fig.add_subplot()
    bins = max(5, min(40, int(math.sqrt(values.size)) * 2))
    ax.hist(values, bins=bins, density=True, color="#8fb3d9", edgecolor="white",
            label=f"estimates ({values.size})")
    ax.axvline(truth, color="black", lw=1.5, label="truth")
    if math.isfinite(bound) and bound > 0:
        lo = min(values.min(), truth - 4 * bound)
        hi = max(values.max(), truth + 4 * bound)
        x = np.linspace(lo, hi, 200)
        ax.plot(x, np.exp(-0.5 * ((x - truth) / bound) ** 2) / (bound * math.sqrt(2 * math.pi)),
                color="#c0392b", lw=1.2, label="N(truth, mean bound)")
    ax.set_title(name, fontsize=10)
    ax.tick_params(labelsize=8)
    ax.legend(fontsize=7)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return base64.b64encode(buf.getvalue()).decode()


def _cell(v: object) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return html.escape(str(v))


def render(df: pd.DataFrame, summary: Summary, title: str) -> str:
    """The report as HTML text."""
    head = ["derivative", "truth", "estimated", "mean", "bias", "scatter", "mean bound",
            "scatter/bound", "coverage 95 %", "unidentifiable", "failures"]
    lines = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
             "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:"
             "collapse}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}"
             "img{margin:4px}</style></head><body>",
             f"<h1>{html.escape(title)}</h1>",
             f"<p>{summary.realizations} realizations, {summary.failures} failed"
             + (" (" + ", ".join(f"{k}: {v}" for k, v in summary.failure_reasons.items())
                + ")" if summary.failure_reasons else "") + "</p>",
             "<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>"]
    for r in summary.rows:
        cells = [r.name, r.truth, r.estimated, r.mean, r.bias, r.scatter, r.mean_bound,
                 r.ratio, r.coverage, r.unidentifiable, r.failures]
        lines.append("<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in cells) + "</tr>")
    lines.append("</table><h2>Estimates</h2><div>")
    est = df[df["status"] == STATUS_ESTIMATED]
    for r in summary.rows:
        values = est.loc[est["name"] == r.name, "estimate"].to_numpy(float)
        if values.size:
            png = _figure(r.name, values, r.truth, r.mean_bound)
            lines.append(f"<img alt='{html.escape(r.name)}' src='data:image/png;base64,{png}'>")
    lines.append("</div></body></html>")
    return "\n".join(lines)


def write_report(study_dir: str | Path, df: pd.DataFrame, summary: Summary,
                 title: str = "Monte Carlo study") -> Path:
    """Write STUDY/report.html and return its path."""
    path = Path(study_dir) / REPORT
    path.write_text(render(df, summary, title), encoding="utf-8")
    return path
