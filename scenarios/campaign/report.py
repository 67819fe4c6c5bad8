"""DIR/report.html of a campaign: the per-point table (share of the estimates within 3
standard errors of the truth) and, per derivative, its flight estimates with their
bounds against the condition, the model's curve from the JSBSim tables, and the
difference. Figures are ``matplotlib.figure.Figure``s, written beside the report as
DIR/derivative-<name>.png and embedded in it as base64 PNG (the HTML stands alone).
"""

from __future__ import annotations

import html
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from flightid.derivatives import unit
from flightid.identification.evaluation.embed import png_img
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.scenarios.campaign.card import Campaign

REPORT = "report.html"
N_SIGMA = 3.0
# x axis: column, label, scale from the stored unit (rad -> deg)
X_AXES = {"speed": ("true airspeed [m/s]", 1.0), "altitude": ("altitude [m]", 1.0),
          "alpha": ("trim angle of attack [deg]", 180.0 / math.pi),
          "flaps": ("flaps [deg]", 180.0 / math.pi), "mass": ("mass scale [1]", 1.0),
          "cg_x": ("CG shift forward [m]", 1.0)}


@dataclass
class PointScore:
    """One test point: its condition, how many derivatives it estimated and how many lie
    within ``N_SIGMA`` standard errors of the truth."""

    index: int
    altitude: float
    speed: float
    alpha: float
    estimated: int
    within: int
    worst: str
    failed: str = ""

    @property
    def share(self) -> float:
        """The share within N_SIGMA (nan when nothing was estimated)."""
        return self.within / self.estimated if self.estimated else math.nan


def point_scores(df: pd.DataFrame) -> list[PointScore]:
    """Per test point, the share of the estimates within 3 sigma of the truth.

    Parameters
    ----------
    df : pandas.DataFrame
        The estimates table (columns ``index``, ``status``, ``sigmas``, ...).

    Returns
    -------
    list[PointScore]
        One score per test point, by index.
    """
    out = []
    for index, rows in df.groupby("index", sort=True):
        first = rows.iloc[0]
        est = rows[rows["status"] == STATUS_ESTIMATED]
        if est.empty:
            out.append(PointScore(int(index), first["altitude"], first["speed"], first["alpha"],
                                  0, 0, "", str(first["reason"])))
            continue
        z = est["sigmas"].abs()
        worst = est.loc[z.idxmax()]
        out.append(PointScore(int(index), float(first["altitude"]), float(first["speed"]),
                              float(first["alpha"]), len(est), int((z <= N_SIGMA).sum()),
                              f"{worst['name']} {worst['sigmas']:+.1f}"))
    return out


def figure_name(derivative: str) -> str:
    """The file name of a derivative's figure beside the report.

    Parameters
    ----------
    derivative : str
        Derivative name.

    Returns
    -------
    str
        File name, characters outside ``[A-Za-z0-9_.-]`` replaced by ``_``.
    """
    return f"derivative-{re.sub(r'[^A-Za-z0-9_.-]', '_', derivative)}.png"


def derivative_figure(name: str, points: pd.DataFrame, curve: pd.DataFrame, x: str,
                      updated: pd.DataFrame | None = None) -> Figure:
    """Top: the flight estimates of ``name`` with +-3 standard errors against ``x``, the
    model's curve, and the truth of the flown aircraft where it differs from the model;
    bottom: estimate minus model (the flight's correction to the tables). ``updated``:
    the updated model's curve (same columns as ``curve``), drawn when given.

    Parameters
    ----------
    name : str
        Derivative name.
    points : pandas.DataFrame
        The estimates table.
    curve : pandas.DataFrame
        The model curve.
    x : str
        Column on the x axis, e.g. ``"speed"`` or ``"alpha"``.
    updated : pandas.DataFrame or None, optional
        The updated model's curve; None draws none.

    Returns
    -------
    matplotlib.figure.Figure
        The two-panel figure.
    """
    label, scale = X_AXES[x]
    u = unit(name)
    ulabel = f" [{u}]" if u else ""
    fig = Figure(figsize=(6.0, 5.0), dpi=100)
    fig.subplots_adjust(left=0.15, right=0.97, bottom=0.1, top=0.93, hspace=0.08)
    top, bottom = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2)
    bottom.sharex(top)
    c = curve[curve["name"] == name].sort_values(x)
    if not c.empty:
        top.plot(c[x] * scale, c["model"], color="#555555", lw=1.5,
                 label="model (JSBSim tables)")
    if updated is not None:
        uc = updated[updated["name"] == name].sort_values(x)
        if not uc.empty:
            top.plot(uc[x] * scale, uc["model"], color="#2e86c1", lw=1.2, ls="--",
                     label="updated model")
            if not c.empty:
                merged = np.interp(uc[x], c[x], c["model"])
                bottom.plot(uc[x] * scale, uc["model"] - merged, color="#2e86c1", lw=1.2,
                            ls="--", label="update - model")
    p = points[(points["name"] == name) & (points["status"] == STATUS_ESTIMATED)]
    xs = p[x].to_numpy() * scale
    top.errorbar(xs, p["estimate"], yerr=N_SIGMA * p["std"], fmt="o", color="#c0392b",
                 ms=4, capsize=3, label=f"flight estimate +-{N_SIGMA:g} sigma")
    if not np.allclose(p["truth"], p["model"], rtol=1e-6, atol=1e-9, equal_nan=True):
        top.plot(xs, p["truth"], "x", color="black", label="flown aircraft (truth)")
        bottom.plot(xs, p["truth"] - p["model"], "x", color="black", label="truth - model")
    bottom.errorbar(xs, p["estimate"] - p["model"], yerr=N_SIGMA * p["std"], fmt="o",
                    color="#c0392b", ms=4, capsize=3, label="estimate - model")
    bottom.axhline(0.0, color="#555555", lw=0.8)
    top.set_title(f"{name} across the test points", fontsize=10)
    top.set_ylabel(f"{name}{ulabel}", fontsize=8)
    bottom.set_ylabel(f"difference{ulabel}", fontsize=8)
    bottom.set_xlabel(label, fontsize=8)
    top.tick_params(labelbottom=False, labelsize=7)
    bottom.tick_params(labelsize=7)
    top.legend(fontsize=7)
    bottom.legend(fontsize=7)
    return fig


def write_report(folder: str | Path, campaign: Campaign, df: pd.DataFrame,
                 curve: pd.DataFrame, notes: list[str] | None = None,
                 updated: pd.DataFrame | None = None) -> Path:
    """Write DIR/report.html (and the PNG figures beside it); its path.

    Parameters
    ----------
    folder : str or Path
        Campaign output folder DIR.
    campaign : Campaign
        The campaign.
    df : pandas.DataFrame
        The estimates table.
    curve : pandas.DataFrame
        The model curve.
    notes : list[str] or None, optional
        Paragraphs added to the report.
    updated : pandas.DataFrame or None, optional
        The updated model's curve, drawn in the figures when given.

    Returns
    -------
    Path
        The report's path.
    """
    folder = Path(folder)
    scores = point_scores(df)
    rows = []
    for s in scores:
        share = "-" if math.isnan(s.share) else f"{100 * s.share:.0f} %"
        rows.append(f"<tr><td>{s.index}</td><td>{s.altitude:g}</td><td>{s.speed:g}</td>"
                    f"<td>{math.degrees(s.alpha):.2f}</td><td>{s.estimated}</td>"
                    f"<td>{s.within}</td><td>{share}</td>"
                    f"<td>{html.escape(s.worst or s.failed)}</td></tr>")
    figures = []
    names = sorted(df.loc[df["status"] == STATUS_ESTIMATED, "name"].unique())
    for name in names:
        fig = derivative_figure(name, df, curve, campaign.x, updated)
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        (folder / figure_name(name)).write_bytes(buf.getvalue())
        figures.append(f"<figure>{png_img(buf.getvalue(), name)}</figure>")
    note_html = "".join(f"<p>{html.escape(n)}</p>" for n in notes or [])
    text = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>campaign {html.escape(campaign.name)}</title>
<style>body{{font-family:sans-serif;max-width:1300px;margin:1em auto}}
table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}
figure{{display:inline-block;margin:4px}}</style></head><body>
<h1>Campaign {html.escape(campaign.name)}</h1>
<p>{html.escape(campaign.description)}</p>
<p>method {html.escape(campaign.method)}, model {html.escape(campaign.model)};
{len(campaign.points)} test points; estimates within {N_SIGMA:g} standard errors of the
flown aircraft's exact derivatives (JSBSim, body axes).</p>{note_html}
<table><tr><th>point</th><th>altitude [m]</th><th>speed [m/s]</th><th>trim alpha [deg]</th>
<th>estimated</th><th>within {N_SIGMA:g} sigma</th><th>share</th><th>worst (sigma) or
failure</th></tr>
{''.join(rows)}</table>
<h2>Derivatives against the condition</h2>
<p>Top: flight estimates with +-{N_SIGMA:g} standard errors, the model's curve from the
JSBSim tables between the points. Bottom: estimate minus model.</p>
{''.join(figures)}
</body></html>
"""
    path = folder / REPORT
    path.write_text(text, encoding="utf-8")
    return path
