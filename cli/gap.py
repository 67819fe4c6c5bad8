"""``flightid gap``: the sim-to-real gap diagnosis printed as a table or JSON, with an
HTML report and the corrected aircraft optionally written (printing only; the work is
``flightid.api.gap``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.api import gap
from flightid.cli import study_options as opts
from flightid.cli.checks import Output, check_choice, check_paths, read_record
from flightid.files import json_safe
from flightid.identification.gap import write_aircraft
from flightid.identification.gap.diagnosis import GapResult, injected
from flightid.identification.gap.envelope import (
    conditions,
    envelope,
    write_envelope_aircraft,
)
from flightid.identification.gap.jsbsim.refly import refly
from flightid.identification.gap.jsbsim.symmetry import even_terms
from flightid.identification.gap.report import write_report
from flightid.identification.gap.sequence import shrink_text
from flightid.identification.gap.verdict import ChannelTest, p_text


def gap_command(
    records: Annotated[list[str], typer.Argument(help="flight records (.parquet, .csv, .mat)")],
    model: Annotated[str, typer.Option("--model", help="JSBSim aircraft: project name, stock "
                                       "name (e.g. DHC6) or XML path")],
    validate: Annotated[list[str] | None, typer.Option(
        "--validate", help="records held out of the fit (default: each maneuver window in "
                           "turn)")] = None,
    report: Annotated[str | None, typer.Option("--report", help="write an HTML report")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    write: Annotated[str | None, typer.Option(
        "--write-aircraft", help="write the aircraft with the named effect here, and fly it "
                                 "again in JSBSim with the records' inputs")] = None,
    refine: Annotated[bool, typer.Option(
        "--refine", help="refit the named airframe effect with the JSBSim aircraft flown "
                         "from the record's measured surfaces (5-20 s more)")] = False,
    axis: Annotated[str, typer.Option(
        "--axis", help="lateral, longitudinal or both (each axis the records excite)")
    ] = "both",
    surfaces: Annotated[str | None, typer.Option(
        "--surfaces", help="what the records' surface channels hold: position or command "
                           "(default: their metadata, else position); on commands the "
                           "actuator effects are candidates")] = None,
    force: opts.Force = False,
) -> None:
    """Is there a gap between a JSBSim model and flight data; where it lies, which
    catalogue effect causes it, and how far it shrinks on held-out data (each axis)."""
    check_choice("--format", format, ("table", "json"))
    if axis not in ("both", "lateral", "longitudinal"):
        raise ValueError(f"--axis must be lateral, longitudinal or both, got {axis!r}")
    if surfaces not in (None, "position", "command"):
        raise ValueError(f"--surfaces must be position or command, got {surfaces!r}")
    check_paths({"RECORDS": records, "--validate": validate, "--model": model},
                [Output("--report", report, "html"),
                 Output("--write-aircraft", write, folder=True)], force)
    # each record read once: resource guard, unit check, jitter re-gridded
    recs = [read_record(path, "gap", force=force) for path in records]
    vals = [read_record(path, "gap", force=force) for path in validate or []]
    stems = [Path(p).stem for p in records]
    if len(conditions(recs, stems)) > 1:  # several conditions: each its own linearisation
        if vals or refine or report:
            raise ValueError("--validate, --refine and --report take records of one "
                             "condition; these records were flown at several (airspeed, "
                             "altitude or flaps): each condition is held out on its own "
                             "maneuvers")
        _envelope(recs, stems, model, axis, surfaces, write, format)
        return
    result = gap(recs, model, validate=vals or None, refine=refine, axis=axis, surfaces=surfaces,
                 names=stems,
                 validate_names=[f"validate {Path(p).stem}" for p in validate or []])
    written = write_aircraft(result, write) if write else None
    # the corrected aircraft and the one as is, flown in JSBSim with each record's inputs
    again = refly(result, recs, write, written) if written else None
    if report:
        write_report(result, report, records, validate or None, again)
    if format == "json":
        d = result.to_json()
        d["injected"] = injected(recs)
        if written:
            d["aircraft_written"] = str(written)
            d["refly"] = json_safe(again)
        print(json.dumps(d, indent=2))
        return
    console = Console()
    for axis, g in result.axes().items():
        _print_axis(console, axis, g)
    for axis, why in result.undiagnosed.items():
        console.print(f"{axis}: not diagnosed: {why}")
    shown = injected(recs)
    if shown:
        console.print("injected (the record's card says): " + "; ".join(shown))
        console.print("named: " + ("; ".join(r.candidate.label for r in result.named_all())
                                   or "nothing"))
    if result.refined is not None:
        f = result.refined
        console.print(f"refined with JSBSim ({f.flights} flights): " + "; ".join(
            f"{n} {v['value']:.4g} ± {v['std']:.2g} (linear {f.linear[n]['value']:.4g})"
            for n, v in f.parameters.items()))
    elif result.refine_note:
        console.print(result.refine_note)
    if written:
        console.print(f"corrected aircraft: {written}")
        if again:
            _print_refly(console, again)


def _envelope(recs: list, stems: list[str], model: str, axis: str, surfaces: str | None,
              write: str | None, format: str) -> None:
    """Records from several conditions: each diagnosed at its own condition, the regime
    bins and the derivative trends (``identification.gap.envelope``)."""
    result = envelope(recs, model, names=stems, axis=axis, surfaces=surfaces)
    written = write_envelope_aircraft(result, write) if write else None
    if format == "json":
        d = result.to_json()
        d["injected"] = injected(recs)
        d["aircraft_written"] = str(written) if written else None
        print(json.dumps(d, indent=2))
        return
    console = Console()
    console.print(f"verdict (the most severe of {len(result.conditions)} conditions): "
                  f"{VERDICT_TEXT.get(result.verdict, result.verdict)}")
    t = Table(title="per condition (gap above the null level of the model as is)")
    for col in ("condition", "axis", "verdict", "above null", "named"):
        t.add_column(col, overflow="fold")
    for row in result.to_json()["conditions"]:
        for a, g in row["axes"].items():
            above = g["above_null"]
            t.add_row(row["label"], a[:3], g["verdict"],
                      "-" if above is None else f"{above:.4f}", "; ".join(g["named"]) or "-")
    console.print(t)
    b = Table(title="where in the envelope (bins of conditions)")
    for col in ("regime", "bin", "axis", "verdicts", "above null"):
        b.add_column(col, overflow="fold")
    for r in result.bins:
        span = (f"{r['low']:.3g}" if r["low"] == r["high"]
                else f"{r['low']:.3g} to {r['high']:.3g}")
        b.add_row(r["variable"], f"{span} {r['unit']}", r["axis"][:3],
                  ", ".join(r["verdicts"]), f"{r['above_null']:.4f}")
    console.print(b)
    for tr in result.trends:
        where = "; ".join(f"{p.delta:+.4f} ± {p.std:.1g} at {p.condition}" for p in tr.points)
        console.print(f"{tr.axis} {tr.derivative} ({tr.axes} axes) delta: {where}")
        console.print(f"  trend: {tr.slope_text()} -> named {tr.label()}"
                      + (f" ({tr.note})" if tr.note else ""))
    if written:
        console.print(f"corrected aircraft: {written}")


def _print_refly(console: Console, again: dict) -> None:
    """The re-fly's windows: gap before and after, bank error, departures."""
    t = Table(title="flown again in JSBSim, each window from the record's state, "
                    "surface offsets refitted (gap: residual / measured energy)")
    for col in ("window", "as is", "corrected", "bank err. deg"):
        t.add_column(col, overflow="fold", justify="left" if col == "window" else "right")
    for w in again["windows"]:
        cells = []
        for key in ("before", "after"):
            gaps = [v for v in w[key].values() if v == v]
            cells.append(f"departed {_departure_time(w[f'{key}_departed'])}"
                         if f"{key}_departed" in w else f"{sum(gaps) / len(gaps):.3f}"
                         if gaps else "-")
        bank = [w.get(f"{k}_bank_error_deg") for k in ("before", "after")]
        cells.append(" -> ".join("-" if b is None else f"{b:.1f}" for b in bank))
        t.add_row(f"{w['axis'][:3]} {w['window']}", *cells)
    console.print(t)
    o = again.get("overall")
    if o:
        console.print(f"overall: gap {o['before']:.3f} (as is) -> {o['after']:.3f} "
                      f"(corrected), {shrink_text(o['shrink'])} shrink, over the windows "
                      "where neither departs. Beside the linear held-out shrink: the "
                      "full nonlinear aircraft, open loop over each whole window.")


def _departure_time(text: str) -> str:
    """'at t = 8.5 s' from a DepartureError's message."""
    head = text.split(":", 1)[0]
    return head.replace("departure ", "")


VERDICT_TEXT = {
    "no_gap": "no gap: the model's residual is at the null level of noise and turbulence",
    "explained": "explained: the model with the named effects is at the null level",
    "partly_unexplained": "partly unexplained: the named effects leave a gap above the null "
                          "level (an effect outside the catalogue is likely)",
    "unexplained": "unexplained: a gap above the null level that no catalogue effect closes",
}


PARAMETERS_WIDTH = 16  # the effects table's parameters column, characters


def _channel_text(channel: str, test: ChannelTest) -> str:
    """One channel's null-level test in a few words: p and share of the main test, of the
    test without the other outputs' residuals, and whether the channel is a gap."""
    text = f"{channel} -" if test.slow else f"{channel} {p_text(test.p_value)} {test.share:+.4f}"
    if test.plain is not None:
        text += f" (alone {p_text(test.plain.p_value)} {test.plain.share:+.4f})"
    return text + (" GAP" if test.gap else "")


def _print_axis(console: Console, axis: str, g: GapResult) -> None:
    """One axis: its verdict, gap map, ranked effects and how far the gap shrinks."""
    console.rule(f"{axis} axis")
    console.print(f"verdict: {VERDICT_TEXT.get(g.verdict, g.verdict)}")
    for term in even_terms(g.linearised.kinks, g.linearised.axes):
        console.print(f"model note: {term.text()}; removed from a written aircraft")
    if g.null_before is not None:
        tests = g.null_before.channels
        console.print("null-level test of the model as is (p-value, input-explained share;"
                      " 'alone': without the other outputs' residuals; '-': an attitude or"
                      " airspeed, high band only; GAP: above the null level): " + ", ".join(
                          _channel_text(c, t) for c, t in tests.items()))
    if g.structure is not None and (g.structure.gap or g.structure.sensor):
        console.print(f"structure outside the catalogue: {g.structure.text()}")
    t = Table(title="gap map (residual / measured energy, mean over windows)")
    per = {c: d for c, d in g.where.by_channel().items() if c in g.linearised.model.outputs}
    cols = list(next(iter(per.values()))) if per else []
    t.add_column("channel")
    for c in cols:
        t.add_column(c, justify="right")
    for ch, d in per.items():
        t.add_row(ch, *(f"{d[c]:.3f}" for c in cols))
    console.print(t)
    for o in g.trim:
        if o.named:
            console.print(f"named at trim level: {o.text()}")
    if g.trim_note:
        console.print(f"trim-level check: {g.trim_note}")
    if g.line is not None and g.line.named:
        console.print(f"named from a spectral line: {g.line.text()}")
    elif g.line is not None and g.line.resonance:
        console.print(f"structure outside the catalogue: {g.line.resonance_text()}")
    if g.verdict == "no_gap" or not g.named and (not g.null_before or not g.null_before.gap):
        return
    named = {r.candidate.label: k for k, r in enumerate(g.named, start=1)}
    e = Table(title=f"effects ({g.evidence}; named first, then by delta BIC; parameters "
                    "in the catalogue's units; shrink: of the held-out gap)")
    rows = [*g.named, *(r for r in (g.pairs + g.effects) if r.candidate.label not in named)]
    # an effect's name on one line where the console's width allows it (the parameters
    # wrap instead): what the other columns, their padding and the borders leave
    longest = max((len(r.candidate.label) for r in rows[:8]), default=6)
    dbic = max((len(f"{r.delta_bic:.0f}") for r in rows[:8]), default=4)
    room = console.width - 6 - (PARAMETERS_WIDTH + 2) - (max(dbic, 4) + 2) - 8 - 8 - 2
    e.add_column("effect", overflow="fold", min_width=max(min(longest, room), 6))
    e.add_column("parameters", overflow="fold", max_width=PARAMETERS_WIDTH)
    e.add_column("dBIC", justify="right")
    e.add_column("shrink", justify="right")
    e.add_column("named", justify="right")
    notes: list[str] = []
    for r in rows[:8]:
        params = "; ".join(f"{_short(k)} {v['value']:.4g} ± {v['std']:.2g}"
                           for k, v in r.parameters.items())
        if r.candidate.label in named:
            mark = str(named[r.candidate.label])
        elif r.note:
            notes.append(f"[{len(notes) + 1}] {r.candidate.label}: {r.note}")
            mark = f"no [{len(notes)}]"
        else:
            mark = "no"
        e.add_row(r.candidate.label, params, f"{r.delta_bic:.0f}", shrink_text(r.shrink), mark)
    console.print(e)
    for line in notes:
        console.print(line)
    s = g.shrinkage()
    if g.named and s:
        console.print(f"named: {s['effect']}; held-out gap {s['overall']['before']:.3f} -> "
                      f"{s['overall']['after']:.3f} ({shrink_text(s['overall']['shrink'])} "
                      "shrink)")
    for r in g.named:
        if r.note:
            console.print(f"{r.candidate.label}: {r.note}")
        if r.equivalent:
            console.print(f"{r.candidate.label}: {r.equivalent}")
        if r.alternatives:
            console.print(f"{r.candidate.label}: not told apart on held-out data from "
                          + ", ".join(a.candidate.label for a in r.alternatives))
    if g.null_after is not None and g.null_after.gap:
        console.print("above the null level after the named effects: "
                      + ", ".join(g.null_after.gap_channels()))
    if g.not_identifiable:
        console.print(f"not identifiable from this record ({len(g.not_identifiable)} "
                      "catalogue entries; the reasons in --format json, 'not_identifiable'): "
                      + ", ".join(g.not_identifiable))


def _short(key: str) -> str:
    """A pair's parameter key without the repeated entry name:
    "derivative_delta(Cn_beta,body).delta" -> "Cn_beta.delta"."""
    label, dot, name = key.rpartition(".")
    if not dot or "(" not in label:
        return key
    entry, _, opts = label.partition("(")
    first = opts.rstrip(")").split(",")[0]
    return f"{first or entry}.{name}"


