"""The HTML report of a gap diagnosis: the gap map, the ranked effects with their
evidence and parameters, the shrink on held-out data, the time histories of the held-out
windows (measured, the model as is, the model with the named effects) and what stays
unexplained."""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.evaluation.embed import png_img
from flightid.identification.gap.diagnosis import GapResult
from flightid.identification.gap.fit import held
from flightid.identification.gap.ranked import Ranked
from flightid.identification.gap.segments import Segment, segments
from flightid.identification.gap.sequence import fixed, shrink_text
from flightid.record import FlightRecord, read

MAX_WINDOWS = 3  # held-out windows drawn
ANGLES = ("beta", "p", "r", "phi", "alpha", "q", "theta")  # drawn in deg (deg/s)
UNITS = {"beta": "deg", "phi": "deg", "alpha": "deg", "theta": "deg", "p": "deg/s",
         "r": "deg/s", "q": "deg/s", "V": "m/s"}

Records = Sequence[FlightRecord | str | Path]


def _loaded(items: Records, prefix: str = "") -> tuple[list[FlightRecord], list[str]]:
    recs = [i if isinstance(i, FlightRecord) else read(i) for i in items]
    names = [f"{prefix}{Path(i).stem}" if not isinstance(i, FlightRecord)
             else f"{prefix}record {k + 1}" for k, i in enumerate(items)]
    return recs, names


def held_out_windows(result: GapResult, records: Records, validate: Records | None = None
                     ) -> list[Segment]:
    """The windows ``result`` held out, cut again from ``records`` (or ``validate``) as the
    diagnosis cut them; every window when the labels do not match.

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    records, validate : records or paths
        Those diagnosed, and the validation records.

    Returns
    -------
    list of Segment
    """
    recs, names = _loaded(validate, "validate ") if validate else _loaded(records)
    windows = segments(recs, names, AXIS_INPUTS[result.axis])
    chosen = [w for w in windows if w.label in set(result.windows.get("held_out", []))]
    return chosen or windows


def time_histories(result: GapResult, records: Records, validate: Records | None = None
                   ) -> Figure:
    """Per held-out window (at most ``MAX_WINDOWS``) and output: measured, the model as is
    and the model with every named effect (at the values fitted on all windows; the
    nuisance biases and initial state refitted on the window, as in the held-out check).

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    records, validate : records or paths
        Those diagnosed, and the validation records.

    Returns
    -------
    Figure
    """
    windows = held_out_windows(result, records, validate)[:MAX_WINDOWS]
    lin = result.linearised
    corrected = lin
    for effect in result.named:
        corrected = fixed(corrected, effect)
    outputs = list(lin.model.outputs)
    fig = Figure(figsize=(4.2 * len(windows) + 0.8, 1.7 * len(outputs) + 0.9),
                 layout="constrained")
    axes = np.atleast_2d(fig.subplots(len(outputs), len(windows), sharex="col",
                                      squeeze=False))
    for j, w in enumerate(windows):
        before = held(lin.model, {}, w.record)
        after = held(corrected.model, {}, w.record) if result.named else None
        t = before.time
        for i, ch in enumerate(outputs):
            k = math.degrees(1.0) if ch in ANGLES else 1.0
            ax = axes[i, j]
            ax.plot(t, k * before.measured[ch], color="black", lw=1.0, label="measured")
            ax.plot(t, k * before.model[ch], color="tab:red", lw=1.0, ls="--",
                    label=f"model as is ({before.fractions()[ch]:.3f})")
            if after is not None:
                ax.plot(after.time, k * after.model[ch], color="tab:blue", lw=1.0,
                        label=f"with named ({after.fractions()[ch]:.3f})")
            unit = UNITS.get(ch, "m/s²")
            ax.set_ylabel(f"{ch} ({unit})" if j == 0 else "", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.legend(fontsize=6, loc="best", frameon=False)
            if i == 0:
                ax.set_title(f"held out: {w.label}", fontsize=9)
        axes[-1, j].set_xlabel("time (s)", fontsize=8)
    named = " then ".join(r.candidate.label for r in result.named) or "nothing (unexplained)"
    fig.suptitle(f"{result.aircraft}: held-out windows; named {named} "
                 "(legend: residual / measured energy)", fontsize=9)
    return fig


def _f(x: float | None, fmt: str = ".4g") -> str:
    return "-" if x is None else format(x, fmt)



def html_report(result: GapResult, records: Records | None = None,
                validate: Records | None = None, refly: dict | None = None) -> str:
    """The report as one self-contained HTML page; with ``records`` (those diagnosed), the
    time histories of the held-out windows; with ``refly`` (``jsbsim.refly``), the gap of
    the corrected aircraft flown again in JSBSim.

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    records, validate : records, paths or None
        Those diagnosed, and the validation records.
    refly : dict or None
        ``jsbsim.refly``'s result.

    Returns
    -------
    str
        The HTML page.
    """
    d = result.to_json()
    named_labels = {r.candidate.label: k for k, r in enumerate(result.named_all(), start=1)}
    rows = []
    for i, e in enumerate(d["effects"] + d["pairs"]):
        params = "; ".join(f"{k} = {_f(v['value'])} &plusmn; {_f(v['std'])}"
                           for k, v in e["parameters"].items())
        ev = e["evidence"]
        step = named_labels.get(e["label"])
        rows.append(f"<tr><td>{i + 1}</td><td>{html.escape(e['label'])}</td><td>{params}</td>"
                    f"<td>{_f(ev['delta_bic'], '.1f')}</td><td>{shrink_text(ev['heldout_shrink'])}"
                    f"</td><td>{step if step else 'no'}</td></tr>")
    verdicts = "".join(
        f"<tr><td>{a}</td><td><b>{html.escape(g.verdict)}</b></td><td>"
        f"{html.escape(g.evidence)}</td><td>"
        + html.escape(", ".join([*(_with_alternatives(r) for r in g.named), *_line(g)])
                      or "-") + "</td></tr>"
        for a, g in result.axes().items())
    verdicts += "".join(f"<tr><td>{a}</td><td>not diagnosed</td><td colspan=2>"
                        f"{html.escape(why)}</td></tr>" for a, why in result.undiagnosed.items())
    shrink = d["shrinkage"]
    srows = "".join(f"<tr><td>{c}</td><td>{_f(v['before'], '.3f')}</td><td>"
                    f"{_f(v['after'], '.3f')}</td><td>{_f(v['shrink'], '.1%')}</td></tr>"
                    for c, v in (shrink.get("channels") or {}).items())
    named = (html.escape(result.named[0].candidate.label) if result.named
             else "unexplained: no candidate shrinks the held-out gap")
    unexpl = ""
    if d["partly_unexplained"]:
        unexpl = ("<p><b>Partly unexplained</b>: the named effects leave "
                  f"{_f(d['partly_unexplained']['share'], '.0%')} of the held-out gap above the "
                  "noise floor (an effect outside the catalogue is likely); above the floor: "
                  + ", ".join(f"{c} {_f(v, '.3f')}" for c, v in
                              d["partly_unexplained"]["remaining_above_floor"].items()) + "</p>")
    if d["refined"]:
        r = d["refined"]
        unexpl += ("<p><b>Refined with JSBSim</b> (the aircraft flown from the record's "
                   f"measured surfaces, {r['flights']} flights): " + "; ".join(
                       f"{k} = {_f(v['value'])} &plusmn; {_f(v['std'])} (ranking "
                       f"{_f(r['linear'][k]['value'])})" for k, v in r["parameters"].items())
                   + "</p>")
    elif d["refine_note"]:
        unexpl += f"<p>{html.escape(d['refine_note'])}</p>"
    if d["unexplained"]:
        unexpl = "<p>Remaining held-out residual by channel: " + ", ".join(
            f"{c} {_f(v, '.3f')}" for c, v in d["unexplained"]["remaining"].items()) + "</p>"
    return f"""<!doctype html><html><head><meta charset="utf-8">
<title>flightid gap: {html.escape(result.aircraft)}</title>
<style>body{{font-family:sans-serif;max-width:70em}}td,th{{padding:2px 8px;
border-bottom:1px solid #ddd}}</style></head><body>
<h1>Sim-to-real gap: {html.escape(result.aircraft)}</h1>
<h2>Verdict</h2><table><tr><th>axis</th><th>verdict</th><th>evidence</th><th>named</th></tr>
{verdicts}</table><p>no_gap: the model's residual is at the null level of noise and
turbulence; explained: the named effects bring it there; partly_unexplained: they do not;
unexplained: a gap no catalogue effect closes (docs/gap.md).</p>
<p>Windows fitted: {html.escape(', '.join(d['windows']['fit']))}; held out:
{html.escape(', '.join(d['windows']['held_out']) or 'none')}.</p>
<h2>Where</h2>{png_img(result.figure(), "gap map", dpi=100)}
<h2>Which</h2><p>Named: <b>{named}</b></p>
<table><tr><th>#</th><th>effect</th><th>parameters (catalogue units)</th><th>&Delta;BIC</th>
<th>held-out shrink</th><th>named (step)</th></tr>{''.join(rows)}</table>{unexpl}
<h2>How far</h2><p>Held-out gap (residual / measured energy) with
{html.escape(shrink.get('effect', '-'))}:</p>
<table><tr><th>channel</th><th>before</th><th>after</th><th>shrink</th></tr>{srows}</table>
{_histories(result, records, validate)}{_refly(refly)}
</body></html>"""


def _histories(result: GapResult, records: Records | None, validate: Records | None) -> str:
    if not records:
        return ""
    img = png_img(time_histories(result, records, validate), "held-out time histories", dpi=100)
    return ("<h2>Before and after, held out</h2><p>Measured (black), the model as is (red) "
            "and with the named effects at their values fitted on all windows (blue); the "
            "biases and the initial state refitted on each window.</p>" + img)


def _refly(refly: dict | None) -> str:
    if not refly or not refly.get("windows"):
        return ""
    rows = "".join(
        f"<tr><td>{html.escape(w['axis'])} {html.escape(w['window'])}</td><td>{c}</td>"
        f"<td>{_f(v['before'], '.3f')}</td><td>{_f(v['after'], '.3f')}</td>"
        f"<td>{_f(v['shrink'], '.1%')}</td></tr>"
        for w in refly["windows"] for c, v in (w.get("channels") or {}).items())
    departed = "".join(
        f"<li>{html.escape(w['window'])}: {who} departed ({html.escape(w[f'{k}_departed'])})</li>"
        for w in refly["windows"]
        for k, who in (("before", "the aircraft as is"), ("after", "the corrected one"))
        if f"{k}_departed" in w)
    o = refly.get("overall")
    total = (f"gap (residual / measured energy, means removed) {_f(o['before'], '.3f')} "
             f"&rarr; {_f(o['after'], '.3f')} ({_f(o['shrink'], '.1%')} shrink)" if o else
             "no window flown by both without a departure")
    name = html.escape(refly["aircraft"])
    return (f"<h2>The corrected aircraft flown again in JSBSim</h2><p>{name}"
            " and the aircraft as is, each maneuver window flown open loop from the "
            "record's state at its start with its measured surfaces, a constant offset of "
            f"each surface refitted on the window: {total}.</p>"
            f"{'<ul>' + departed + '</ul>' if departed else ''}"
            "<table><tr><th>window</th><th>channel</th>"
            f"<th>before</th><th>after</th><th>shrink</th></tr>{rows}</table>")


def write_report(result: GapResult, path: str | Path, records: Records | None = None,
                 validate: Records | None = None, refly: dict | None = None) -> Path:
    """Write ``html_report`` to ``path``.

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    path : str or Path
        The HTML file written.
    records, validate : records, paths or None
        Those diagnosed, and the validation records.
    refly : dict or None
        ``jsbsim.refly``'s result.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    path.write_text(html_report(result, records, validate, refly))
    return path


def _with_alternatives(r: Ranked) -> str:
    """A named effect's label, with the effects not told apart from it on held-out data."""
    if not r.alternatives:
        return r.candidate.label
    return (f"{r.candidate.label} (not told apart from "
            + ", ".join(a.candidate.label for a in r.alternatives) + ")")


def _line(g: GapResult) -> list[str]:
    """The spectral-line check's finding on one axis (``gap.lines``), as text."""
    if g.line is not None and g.line.named:
        return [g.line.text()]
    if g.line is not None and g.line.resonance:
        return [g.line.resonance_text()]
    return []
