"""``flightid gap``: the sim-to-real gap diagnosis printed as a table or JSON, with an
HTML report and the corrected aircraft optionally written (printing only; the work is
``flightid.api.gap``)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.api import gap
from flightid.cli.checks import Output, check_paths
from flightid.identification.gap import write_aircraft
from flightid.identification.gap.correct import refly
from flightid.identification.gap.report import write_report
from flightid.record import read


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
) -> None:
    """Where a JSBSim model departs from flight data, which catalogue effect causes it, and
    how far the gap shrinks on held-out data (lateral axis)."""
    if format not in ("table", "json"):
        raise ValueError(f"--format must be table or json, got {format!r}")
    check_paths({"RECORDS": records, "--validate": validate, "--model": model},
                [Output("--report", report, "html"),
                 Output("--write-aircraft", write, folder=True)])
    result = gap(records, model, validate=validate or None, refine=refine)
    written = write_aircraft(result, write) if write else None
    # the corrected aircraft and the one as is, flown in JSBSim with each record's inputs
    again = refly(result, [read(r) for r in records], write, written) if written else None
    if report:
        write_report(result, report, records, validate or None, again)
    if format == "json":
        d = result.to_json()
        if written:
            d["aircraft_written"] = str(written)
            d["refly"] = _finite(again)
        print(json.dumps(d, indent=2))
        return
    console = Console()
    s = result.shrinkage()
    t = Table(title=f"gap map: {model} (residual / measured energy, mean over windows)")
    per = result.where.by_channel()
    cols = list(next(iter(per.values())))
    t.add_column("channel")
    for c in cols:
        t.add_column(c, justify="right")
    for ch, d in per.items():
        t.add_row(ch, *(f"{d[c]:.3f}" for c in cols))
    console.print(t)
    e = Table(title="effects (confirmed first, by delta BIC)")
    for c in ("effect", "parameters", "delta BIC", "held-out shrink", "confirmed"):
        e.add_column(c)
    for r in (result.pairs + result.effects)[:10]:
        params = "; ".join(f"{k} {v['value']:.4g} ± {v['std']:.2g}"
                           for k, v in r.parameters.items())
        e.add_row(r.candidate.label, params, f"{r.delta_bic:.1f}", f"{r.shrink:.1%}",
                  "yes" if r.confirmed else "no")
    console.print(e)
    for k, step in enumerate(s.get("steps", [])[1:], start=2):
        r = result.named[k - 1]
        params = "; ".join(f"{n} {v['value']:.4g} ± {v['std']:.2g}"
                           for n, v in r.parameters.items())
        console.print(f"step {k} (with the effects before it fixed): {step['effect']} {params}; "
                      f"held-out gap -> {step['after']:.3f}")
    if result.named and s:
        console.print(f"named: {s['effect']}; held-out gap "
                      f"{s['overall']['before']:.3f} -> {s['overall']['after']:.3f} "
                      f"({s['overall']['shrink']:.1%} shrink)")
    else:
        console.print("unexplained: no candidate shrinks the held-out gap; remaining: "
                      + ", ".join(f"{c} {v:.3f}" for c, v in result.remaining().items()))
    if result.refined is not None:
        f = result.refined
        console.print(f"refined with JSBSim ({f.flights} flights): " + "; ".join(
            f"{n} {v['value']:.4g} ± {v['std']:.2g} (linear {f.linear[n]['value']:.4g})"
            for n, v in f.parameters.items()))
    elif result.refine_note:
        console.print(result.refine_note)
    if result.partly_unexplained:
        console.print(f"partly unexplained: the named effects leave "
                      f"{result.unexplained_share():.0%} of the held-out gap above the noise "
                      "floor; an effect outside the catalogue is likely (above the floor: "
                      + ", ".join(f"{c} {v:.3f}" for c, v in result.remaining_above_floor().items())
                      + ")")
    if written:
        console.print(f"corrected aircraft: {written}")
        o = (again or {}).get("overall")
        if o:
            console.print(f"flown again in JSBSim with the records' inputs (open loop from "
                          f"trim): gap {o['before']:.3f} (as is) -> {o['after']:.3f} "
                          f"(corrected), {o['shrink']:.1%} shrink")
        for r in (again or {}).get("records", []):
            for key, name in (("before", "the aircraft as is"), ("after", "the corrected one")):
                if f"{key}_departed" in r:
                    console.print(f"flown again in JSBSim, record {r['record']}: {name} "
                                  f"departed ({r[f'{key}_departed']})")


def _finite(x: object) -> object:
    """``x`` with NaN and infinities as None (strict JSON)."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
