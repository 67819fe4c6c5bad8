"""STUDY/report.html: the summary table (the coverage with its Clopper-Pearson interval)
and, per derivative, a histogram of the estimates (axes labelled with the derivative's
unit) with the truth and the normal curve the mean reported bound predicts (centred on
the truth); figures drawn with ``matplotlib.figure.Figure``, written beside the report
as STUDY/histogram-<derivative>.png and embedded in it as base64 PNG, so the HTML file
also stands alone; the summary table also as STUDY/summary.csv."""

from __future__ import annotations

import html
import io
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from flightid.derivatives import unit
from flightid.identification.evaluation.embed import png_img
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.scenarios.montecarlo.exports import write_tables
from flightid.scenarios.montecarlo.summary import Summary

REPORT = "report.html"
CSV = "summary.csv"  # the summary's rows beside the report, one per derivative


# the unit of a probability density over a derivative's values: the inverse of its unit
_DENSITY_UNIT = {"1/rad": "rad", "1": "1"}


def histogram_name(derivative: str) -> str:
    """The file name of a derivative's histogram beside the report.

    Parameters
    ----------
    derivative : str
        Derivative name.

    Returns
    -------
    str
        File name, characters outside ``[A-Za-z0-9_.-]`` replaced by ``_``.
    """
    return f"histogram-{re.sub(r'[^A-Za-z0-9_.-]', '_', derivative)}.png"


def histogram(name: str, values: np.ndarray, truth: float, bound: float) -> Figure:
    """The histogram (as a density) of ``values``, the estimates of derivative ``name``,
    with the truth and N(truth, bound); the x axis in the derivative's unit
    (``derivatives.unit``), the y axis in its inverse.

    Parameters
    ----------
    name : str
        Derivative name.
    values : numpy.ndarray
        Its estimates, in its unit; shape (n,).
    truth : float
        True value.
    bound : float
        Mean reported standard error; the normal curve is drawn when finite and > 0.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    u = unit(name)
    # fixed margins: a constrained layout draws every figure twice (half the report's time)
    fig = Figure(figsize=(4.2, 3.0), dpi=100)
    fig.subplots_adjust(left=0.16, right=0.97, bottom=0.16, top=0.9)
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
    ax.set_xlabel(f"estimate of {name} [{u}]" if u else f"estimate of {name}", fontsize=8)
    ax.set_ylabel(f"probability density [{_DENSITY_UNIT[u]}]" if u else
                  f"probability density [1 / unit of {name}]", fontsize=8)
    ax.tick_params(labelsize=8)
    ax.legend(fontsize=7)
    return fig


def _cell(v: object) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return html.escape(str(v))


def render(df: pd.DataFrame, summary: Summary, title: str,
           pngs: dict[str, bytes] | None = None) -> str:
    """The report as HTML text; ``pngs``: each derivative's histogram (``histograms``),
    drawn here when not given.

    Parameters
    ----------
    df : pandas.DataFrame
        The study's rows.
    summary : Summary
        The study's summary.
    title : str
        Report title.
    pngs : dict[str, bytes] or None, optional
        Derivative -> histogram PNG; None draws them.

    Returns
    -------
    str
        HTML text.
    """
    head = ["derivative", "truth", "estimated", "mean", "bias", "scatter", "mean bound",
            "scatter/bound", "coverage of the 95 % intervals",
            "its 95 % interval (Clopper-Pearson)", "unidentifiable", "failures"]
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
                 r.ratio, r.coverage, f"{_cell(r.coverage_low)} - {_cell(r.coverage_high)}",
                 r.unidentifiable, r.failures]
        lines.append("<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in cells) + "</tr>")
    lines.append("</table>" + "".join(f"<p><b>Warning</b>: {html.escape(w)}</p>"
                                     for w in summary.warnings()))
    lines.append("<p>Coverage: the share of the realizations whose 95 % interval "
                 "(estimate +- 1.96 reported std) holds the truth; its interval is the exact "
                 "binomial one of Clopper &amp; Pearson (1934).</p><h2>Estimates</h2><p>"
                 "Each histogram also as histogram-&lt;derivative&gt;.png beside this file."
                 "</p><div>")
    for name, png in (histograms(df, summary) if pngs is None else pngs).items():
        lines.append(png_img(png, name))
    lines.append("</div></body></html>")
    return "\n".join(lines)


def histograms(df: pd.DataFrame, summary: Summary) -> dict[str, bytes]:
    """Each estimated derivative's histogram (``histogram``) as PNG bytes.

    Parameters
    ----------
    df : pandas.DataFrame
        The study's rows.
    summary : Summary
        The study's summary.

    Returns
    -------
    dict[str, bytes]
        Derivative name -> PNG bytes.
    """
    est = df[df["status"] == STATUS_ESTIMATED]
    out = {}
    for r in summary.rows:
        values = est.loc[est["name"] == r.name, "estimate"].to_numpy(float)
        if values.size:
            buf = io.BytesIO()
            histogram(r.name, values, r.truth, r.mean_bound).savefig(buf, format="png")
            out[r.name] = buf.getvalue()
    return out


def write_report(study_dir: str | Path, df: pd.DataFrame, summary: Summary,
                 title: str = "Monte Carlo study") -> Path:
    """Write STUDY/report.html, each histogram beside it (``histogram_name``) and the
    summary's rows as STUDY/summary.csv, .md and .tex (the columns of ``Summary.frame``);
    return the report's path.

    Parameters
    ----------
    study_dir : str or Path
        The study folder STUDY.
    df : pandas.DataFrame
        The study's rows.
    summary : Summary
        The study's summary.
    title : str, optional
        Report title.

    Returns
    -------
    Path
        The report's path.
    """
    if summary.rows:
        summary.frame().to_csv(Path(study_dir) / CSV)
        write_tables(summary.frame(), Path(study_dir) / CSV)
    pngs = histograms(df, summary)
    for name, png in pngs.items():
        (Path(study_dir) / histogram_name(name)).write_bytes(png)
    path = Path(study_dir) / REPORT
    path.write_text(render(df, summary, title, pngs), encoding="utf-8")
    return path
