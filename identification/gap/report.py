"""The HTML report of a gap diagnosis: the gap map, the ranked effects with their
evidence and parameters, the shrink on held-out data and what stays unexplained."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from flightid.identification.gap.diagnose import GapResult


def _png(result: GapResult) -> str:
    buf = io.BytesIO()
    result.figure().savefig(buf, format="png", dpi=100, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode()


def _f(x: float | None, fmt: str = ".4g") -> str:
    return "-" if x is None else format(x, fmt)


def html_report(result: GapResult) -> str:
    """The report as one self-contained HTML page."""
    d = result.to_json()
    rows = []
    for i, e in enumerate(d["effects"] + d["pairs"]):
        params = "; ".join(f"{k} = {_f(v['value'])} &plusmn; {_f(v['std'])}"
                           for k, v in e["parameters"].items())
        ev = e["evidence"]
        rows.append(f"<tr><td>{i + 1}</td><td>{html.escape(e['label'])}</td><td>{params}</td>"
                    f"<td>{_f(ev['delta_bic'], '.1f')}</td><td>{_f(ev['heldout_shrink'], '.1%')}"
                    f"</td><td>{'yes' if ev['confirmed'] else 'no'}</td></tr>")
    shrink = d["shrinkage"]
    srows = "".join(f"<tr><td>{c}</td><td>{_f(v['before'], '.3f')}</td><td>"
                    f"{_f(v['after'], '.3f')}</td><td>{_f(v['shrink'], '.1%')}</td></tr>"
                    for c, v in (shrink.get("channels") or {}).items())
    named = (html.escape(result.named[0].candidate.label) if result.named
             else "unexplained: no candidate shrinks the held-out gap")
    unexpl = ""
    if d["unexplained"]:
        unexpl = "<p>Remaining held-out residual by channel: " + ", ".join(
            f"{c} {_f(v, '.3f')}" for c, v in d["unexplained"]["remaining"].items()) + "</p>"
    return f"""<!doctype html><html><head><meta charset="utf-8">
<title>flightid gap: {html.escape(result.aircraft)}</title>
<style>body{{font-family:sans-serif;max-width:70em}}td,th{{padding:2px 8px;
border-bottom:1px solid #ddd}}</style></head><body>
<h1>Sim-to-real gap: {html.escape(result.aircraft)}</h1>
<p>Windows fitted: {html.escape(', '.join(d['windows']['fit']))}; held out:
{html.escape(', '.join(d['windows']['held_out']) or 'none')}.</p>
<h2>Where</h2><img src="data:image/png;base64,{_png(result)}" alt="gap map">
<h2>Which</h2><p>Named: <b>{named}</b></p>
<table><tr><th>#</th><th>effect</th><th>parameters (catalogue units)</th><th>&Delta;BIC</th>
<th>held-out shrink</th><th>confirmed</th></tr>{''.join(rows)}</table>{unexpl}
<h2>How far</h2><p>Held-out gap (residual / measured energy) with
{html.escape(shrink.get('effect', '-'))}:</p>
<table><tr><th>channel</th><th>before</th><th>after</th><th>shrink</th></tr>{srows}</table>
</body></html>"""


def write_report(result: GapResult, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(html_report(result))
    return path
