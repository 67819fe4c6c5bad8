"""The report of an input-design comparison: a PNG of each derivative's scatter by design
(in the derivative's units, log scale, with its interval and the mean reported bound), the same
figure and the tables in STUDY/design-compare.html, and a Markdown table for docs/."""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from flightid.derivatives import unit
from flightid.identification.evaluation.embed import png_img
from flightid.scenarios.montecarlo.design.comparison import Comparison, compare
from flightid.scenarios.montecarlo.exports import write_tables
from flightid.scenarios.montecarlo.intervals import LEVEL, interval_text, scatter_interval

PNG = "design-compare.png"
HTML = "design-compare.html"
CSV = "design-compare.csv"  # Comparison.frame(): one row per derivative and design
COLORS = {"doublet": "#c0392b", "211": "#e67e22", "3211": "#2e86c1", "sweep": "#27ae60",
          "multisine": "#8e44ad"}


def figure(comparison: Comparison, level: float = LEVEL) -> Figure:
    """Bars: each derivative's scatter by design in the derivative's own units (1/rad or
    dimensionless, ``derivatives.unit``; log scale), so a derivative whose truth is 0
    keeps its bars; whiskers: the scatter's ``level`` interval (chi-square,
    ``intervals.scatter_interval``); dashes: the mean reported bound.

    Parameters
    ----------
    comparison : Comparison
        The design comparison.
    level : float, optional
        Confidence level of the whiskers, 0..1.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    scatter, bound = comparison.table("scatter"), comparison.table("mean_bound")
    count = comparison.table("estimated")
    names = list(scatter.index)
    kinds = list(scatter.columns)
    fig = Figure(figsize=(max(6.0, 1.3 * len(names) + 2), 4.4), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    width = 0.8 / max(1, len(kinds))
    x = np.arange(len(names))
    for j, kind in enumerate(kinds):
        pos = x - 0.4 + width * (j + 0.5)
        s = scatter[kind].to_numpy(float)
        whiskers = np.array([scatter_interval(v, int(c), level) for v, c in
                             zip(s, count[kind].fillna(0).to_numpy(), strict=True)]).T
        ax.bar(pos, s, width, color=COLORS.get(kind), label=kind)
        ax.errorbar(pos, s, yerr=np.abs(whiskers - s), fmt="none", ecolor="0.3", lw=0.8)
        ax.plot(pos, bound[kind].to_numpy(float), "k_", ms=8)
    ax.set_yscale("log")
    ax.set_xticks(x, [f"{n}\n[{unit(str(n)) or '?'}]" for n in names], fontsize=8)
    ax.set_xlabel("derivative [its unit: 1/rad, or 1 for a nondimensional rate]", fontsize=8)
    ax.set_ylabel("scatter of the estimates (derivative's unit, log)")
    ax.set_title(f"{comparison.aircraft} {comparison.model}, {comparison.method}, "
                 f"equal {comparison.equal}, n={comparison.n} per design (bars: scatter, "
                 f"whiskers: its {100 * level:.0f} % interval, dashes: mean bound)",
                 fontsize=8)
    ax.legend(fontsize=8, ncol=len(kinds))
    ax.grid(axis="y", which="both", alpha=0.3)
    return fig


def _cell(v: object) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.4g}"
    return html.escape(str(v))


def costs_rows(comparison: Comparison) -> list[list[object]]:
    """[design, flight time s, input time s, energy rad^2 s, peak deg, realizations,
    failures] per design.

    Parameters
    ----------
    comparison : Comparison
        The design comparison.

    Returns
    -------
    list[list[object]]
        One row per design.
    """
    return [[r.kind, r.flight_time, r.input_time, r.energy, math.degrees(r.peak),
             r.summary.realizations, r.summary.failures] for r in comparison.results]


COST_HEAD = ["design", "flight time (s)", "input time (s)", "input energy (rad² s)",
             "peak (deg)", "realizations", "failures"]


def markdown(comparison: Comparison) -> str:
    """Markdown tables: the designs' costs, then scatter (bias, mean bound) by derivative
    (bold: smaller than every other design's, the ratio's interval below 1), then the
    3211 / doublet scatter ratios with their intervals.

    Parameters
    ----------
    comparison : Comparison
        The design comparison.

    Returns
    -------
    str
        Markdown text.
    """
    lines = ["| " + " | ".join(COST_HEAD) + " |", "|" + "---|" * len(COST_HEAD)]
    for row in costs_rows(comparison):
        lines.append("| " + " | ".join(
            f"{v:.4g}" if isinstance(v, float) else str(v) for v in row) + " |")
    scatter, bias, bound = (comparison.table(c) for c in ("scatter", "bias", "mean_bound"))
    truth = comparison.frame().groupby("derivative")["truth"].first()
    kinds = list(scatter.columns)
    lines += ["", "scatter (bias, mean bound) by design:", "",
              "| derivative | truth | " + " | ".join(kinds) + " |",
              "|---|---|" + "---|" * len(kinds)]
    best = comparison.best()
    for name in scatter.index:
        cells = []
        for k in kinds:
            s = f"{scatter.loc[name, k]:.4f} ({bias.loc[name, k]:+.4f}, {bound.loc[name, k]:.4f})"
            cells.append(f"**{s}**" if k == best[str(name)] else s)
        lines.append(f"| {name} | {truth[name]:+.4f} | " + " | ".join(cells) + " |")
    rows = ratio_rows(comparison)
    if rows:
        lines += ["", f"scatter 3211 / doublet with its {100 * LEVEL:.0f} % interval "
                  "(paired bootstrap over the same seeds where both n are 20 or more, Efron & "
                  "Tibshirani 1993; else F distribution, Montgomery & Runger 2014, 10-5):", "",
                  "| " + " | ".join(RATIO_HEAD) + " |", "|" + "---|" * len(RATIO_HEAD)]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


RATIO_HEAD = ["derivative", "3211 / doublet", "interval", "n 3211", "n doublet", "smaller"]


def ratio_rows(comparison: Comparison) -> list[list[str]]:
    """The 3211 / doublet scatter ratio per derivative both estimated, as text: ratio, its
    interval, the realizations of each and the smaller ("not clear" when the interval
    contains 1); [] without both designs.

    Parameters
    ----------
    comparison : Comparison
        The design comparison.

    Returns
    -------
    list[list[str]]
        One row per derivative: name, ratio, interval, n_a, n_b, the smaller.
    """
    if comparison.verdict("3211", "doublet") is None:
        return []
    return [[str(name), f"{r['ratio']:.3g}", interval_text(r['low'], r['high']),
             str(r["n_a"]), str(r["n_b"]), r["winner"] or "not clear"]
            for name, r in comparison.scatter_ratios("3211", "doublet").iterrows()]


def write(comparison: Comparison, folder: str | Path) -> tuple[Path, Path]:
    """Write FOLDER/design-compare.png, FOLDER/design-compare.html and beside them
    FOLDER/design-compare.csv, .md and .tex (``Comparison.frame``); return the PNG and
    HTML paths.

    Parameters
    ----------
    comparison : Comparison
        The design comparison.
    folder : str or Path
        Output folder FOLDER; created if missing.

    Returns
    -------
    tuple[Path, Path]
        (PNG path, HTML path).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    comparison.frame().to_csv(folder / CSV, index=False)
    write_tables(comparison.frame(), folder / CSV, index=False)
    png = folder / PNG
    figure(comparison).savefig(png)
    scatter, bias, bound = (comparison.table(c) for c in ("scatter", "bias", "mean_bound"))
    kinds = list(scatter.columns)
    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>design-compare"
             "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:"
             "collapse;margin-bottom:1em}td,th{border:1px solid #ccc;padding:2px 8px;"
             "text-align:right}</style></head><body>",
             f"<h1>Input designs: {html.escape(comparison.aircraft)}, "
             f"{html.escape(comparison.model)}, {html.escape(comparison.method)}</h1>",
             f"<p>card {html.escape(comparison.card)}; equal {comparison.equal}"
             + (f" (the energy of the {comparison.reference})"
                if comparison.equal == "energy" else "")
             + f"; {comparison.n} realizations per design, the same seeds for every design."
             "</p><table><tr>" + "".join(f"<th>{h}</th>" for h in COST_HEAD) + "</tr>"]
    for row in costs_rows(comparison):
        parts.append("<tr>" + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>")
    parts.append("</table>")
    for title, table in (("scatter (standard deviation of the estimates)", scatter),
                         ("bias", bias), ("mean reported bound", bound)):
        parts.append(f"<h2>{title}</h2><table><tr><th>derivative</th>"
                     + "".join(f"<th>{k}</th>" for k in kinds) + "</tr>")
        for name in table.index:
            parts.append(f"<tr><td>{html.escape(str(name))}</td>" + "".join(
                f"<td>{_cell(float(table.loc[name, k]))}</td>" for k in kinds) + "</tr>")
        parts.append("</table>")
    rows = ratio_rows(comparison)
    if rows:
        parts.append(f"<h2>scatter 3211 / doublet, {100 * LEVEL:.0f} % interval (F "
                     "distribution)</h2><table><tr>"
                     + "".join(f"<th>{h}</th>" for h in RATIO_HEAD) + "</tr>")
        parts += ["<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in r) + "</tr>" for r in rows]
        parts.append("</table>")
    parts.append(png_img(png, "scatter by design"))
    parts.append("<p>Per design: " + ", ".join(
        f"<a href='{html.escape(r.kind)}/report.html'>{html.escape(r.kind)}</a>"
        for r in comparison.results) + "</p></body></html>")
    page = folder / HTML
    page.write_text("\n".join(parts), encoding="utf-8")
    return png, page


def compare_and_report(study_dir: str | Path = "design-compare", **kwargs: object
                       ) -> tuple[Comparison, Path, Path]:
    """Compare input designs (``design.compare``) and write the comparison's figure and page.

    Parameters
    ----------
    study_dir : str or Path
        Where the studies, the PNG and the HTML page go.
    **kwargs
        ``design.compare``'s keywords (card, designs, n, method, model, ...).

    Returns
    -------
    tuple of (Comparison, Path, Path)
        The comparison, the PNG and the HTML page.
    """
    comparison = compare(study_dir=study_dir, **kwargs)  # type: ignore[arg-type]
    png, page = write(comparison, study_dir)
    return comparison, png, page
