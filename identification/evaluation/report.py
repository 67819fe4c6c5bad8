"""HTML report of identification results: tables and plots in one self-contained file.

Plots (PNG, embedded as base64 so the file opens anywhere): measured vs model time
histories, residuals, and each estimate with its 2-sigma bar against the truth.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from flightid.channels import CHANNELS
from flightid.files import write_text
from flightid.identification.estimate import Estimate
from flightid.identification.evaluation.embed import png_img
from flightid.identification.methods import registry


def time_history_figure(estimate: Estimate, title: str = "") -> Figure:
    """Measured vs model outputs and residuals on a shared time axis (s).

    Frequency-domain estimates get ``frequency_figure`` instead.

    Parameters
    ----------
    estimate : Estimate
        An estimate with per-output series.
    title : str, optional
        The figure title. Default the method and model.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    names = list(estimate.outputs)
    if any("frequency" in estimate.outputs[n] for n in names):
        return frequency_figure(estimate, title)
    fig = Figure(figsize=(11, 1.9 * len(names) + 0.6))
    axes = fig.subplots(len(names), 2, sharex=True, squeeze=False)
    t = estimate.time if estimate.time is not None else np.arange(
        len(next(iter(estimate.outputs.values()))["measured"]))
    for row, name in enumerate(names):
        out = estimate.outputs[name]
        axes[row, 0].plot(t, out["measured"], color="0.3", lw=1.0, label="measured")
        axes[row, 0].plot(t, out["model"], color="tab:red", lw=1.0, ls="--", label="model")
        axes[row, 0].set_ylabel(f"{name} ({_unit(name)})")
        axes[row, 1].plot(t, np.asarray(out["measured"]) - np.asarray(out["model"]),
                          color="tab:blue", lw=0.8)
        axes[row, 1].set_ylabel(f"{name} residual")
        for ax in axes[row]:
            ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    model = estimate.fit.get("model", "")
    axes[0, 0].set_title(title or f"{estimate.method} {model}: measured and model")
    axes[0, 1].set_title("residuals (measured - model)")
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    fig.tight_layout()
    return fig


def frequency_figure(estimate: Estimate, title: str = "") -> Figure:
    """Measured and model magnitudes of each fitted transform or response against frequency
    (Hz), log axes.

    Parameters
    ----------
    estimate : Estimate
        A frequency-domain estimate.
    title : str, optional
        The figure title. Default the method and model.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    names = list(estimate.outputs)
    fig = Figure(figsize=(11, 1.9 * len(names) + 0.6))
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    for ax, name in zip(axes, names, strict=True):
        out = estimate.outputs[name]
        order = np.argsort(out["frequency"])
        f = np.asarray(out["frequency"])[order]
        ax.loglog(f, np.abs(np.asarray(out["measured"]))[order], color="0.3", lw=1.0,
                  label="measured")
        ax.loglog(f, np.abs(np.asarray(out["model"]))[order], color="tab:red", lw=1.0,
                  ls="--", label="model")
        ax.set_ylabel(f"|{name}|")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(title or f"{estimate.method} {estimate.fit.get('model', '')}: "
                               "measured and model, magnitude")
    axes[-1].set_xlabel("frequency (Hz)")
    fig.tight_layout()
    return fig


def estimates_figure(estimate: Estimate, truth: dict[str, float] | None = None) -> Figure:
    """Each derivative against truth: estimate/|truth| with 2-sigma bars, and error/std.

    Parameters
    ----------
    estimate : Estimate
        The estimate; its names starting with "C" are drawn.
    truth : dict of str to float, optional
        True values by name; without it the estimates are scaled by themselves.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    names = [n for n in estimate.names if n.startswith("C")]
    scored = [n for n in names if truth and n in truth]
    fig = Figure(figsize=(11, 0.32 * len(names) + 1.2))
    axes = fig.subplots(1, 2 if scored else 1, sharey=True, squeeze=False)
    ax = axes[0, 0]
    for i, n in enumerate(names):
        v, s = estimate[n], estimate.std_of(n)
        ref = truth.get(n) if truth else None
        scale = abs(ref) if ref else (abs(v) or 1.0)
        ax.errorbar(v / scale, i, xerr=2 * s / scale, fmt="o", color="tab:blue", capsize=3)
        if ref:
            ax.plot(np.sign(ref), i, "k|", ms=14, mew=2)
    ax.set_yticks(np.arange(len(names)), names)
    ax.invert_yaxis()
    ax.axvline(0, color="0.8", lw=0.8)
    ax.set_xlabel("estimate / |truth| (bar: 2 sigma; tick: truth); zero truth: / |estimate|")
    ax.grid(alpha=0.3, axis="x")
    if scored:
        ax = axes[0, 1]
        for i, n in enumerate(names):
            if n in scored and estimate.std_of(n) > 0:
                z = (estimate[n] - truth[n]) / estimate.std_of(n)
                ax.plot(z, i, "o", color="tab:red" if abs(z) > 3 else "tab:green")
        for x in (-3, 3):
            ax.axvline(x, color="tab:red", lw=0.8, ls="--")
        ax.axvline(0, color="0.5", lw=0.8)
        ax.set_xlabel("(estimate - truth) / std  (dashed: 3 sigma)")
        ax.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    return fig


def _method_name(method_id: str) -> str:
    known = registry.methods()
    return known[method_id].name if method_id in known else method_id


def _unit(name: str) -> str:
    return CHANNELS[name].unit if name in CHANNELS else "-"


def _table(rows: Sequence[Sequence[object]], header: Sequence[str]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_fmt(c))}</td>" for c in r) + "</tr>" for r in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _fmt(x: object) -> str:
    if isinstance(x, float | np.floating):
        return "" if not np.isfinite(x) else f"{x:.5g}"
    return str(x)


def write_html(
    path: str | Path,
    title: str,
    estimates: Sequence[Estimate],
    truth: dict[str, float] | None = None,
    notes: Sequence[str] = (),
    figures: Sequence[tuple[str, object]] = (),
) -> Path:
    """Write a self-contained HTML report with tables and plots.

    Parameters
    ----------
    path : str or Path
        The HTML file written.
    title : str
        The report title.
    estimates : sequence of Estimate
        The estimates tabulated and plotted.
    truth : dict of str to float, optional
        True values by name, for the error columns.
    notes : sequence of str, optional
        Paragraphs under the title.
    figures : sequence of tuple of (str, object), optional
        (caption, matplotlib figure or PNG path) pairs added at the end.

    Returns
    -------
    Path
        The path written.
    """
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'>",
        f"<title>{html.escape(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
        "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;"
        "padding:2px 8px;text-align:right}th{background:#eee}img{max-width:100%}</style>",
        f"</head><body><h1>{html.escape(title)}</h1>",
    ]
    parts += [f"<p>{html.escape(n)}</p>" for n in notes]
    for est in estimates:
        model = est.fit.get("model") or est.fit.get("coefficient") or ""
        parts.append(f"<h2>{html.escape(_method_name(est.method))}"
                     f"{': ' + html.escape(str(model)) if model else ''}</h2>")
        rows = []
        for n, v, s in zip(est.names, est.values, est.std, strict=True):
            ref = truth.get(n) if truth else None
            err = v - ref if ref is not None else float("nan")
            rows.append([n, ref if ref is not None else "", v, s, err,
                         abs(err) / s if ref is not None and s > 0 else ""])
        parts.append(_table(rows, ["parameter", "truth", "estimate", "std", "error",
                                   "|error|/std"]))
        if est.unidentifiable:
            parts.append("<p><b>Unidentifiable:</b></p><ul>" + "".join(
                f"<li>{html.escape(k)}: {html.escape(v)}</li>"
                for k, v in est.unidentifiable.items()) + "</ul>")
        fit_rows = [[k, v] for k, v in est.fit.items() if isinstance(v, int | float | str | bool)]
        if fit_rows:
            parts.append(_table(fit_rows, ["fit statistic", "value"]))
        if est.outputs:
            parts.append(png_img(time_history_figure(est), "time histories"))
        if any(n.startswith("C") for n in est.names):
            parts.append(png_img(estimates_figure(est, truth), "estimates"))
    for caption, fig in figures:
        parts.append(f"<h2>{html.escape(caption)}</h2>{png_img(fig, caption)}")
    parts.append("</body></html>")
    path = Path(path)
    return write_text(path, "\n".join(parts), encoding="utf-8")
