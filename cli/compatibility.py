"""``flightid compatibility``: flight path reconstruction printed as a table or JSON, the
corrected record optionally written (printing only; the work is
``flightid.identification.compatibility.reconstruction``)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.cli import study_options as opts
from flightid.cli.checks import (
    Output,
    check_choice,
    check_paths,
    check_suffix,
    printed_warnings,
    read_record,
)
from flightid.identification.compatibility.reconstruction import PARAMETERS, reconstruct
from flightid.identification.data.reduction import calibration_doubts
from flightid.identification.engine import convergence

# display factors to deg, deg/s and g
_DISPLAY = {"rad": 180 / math.pi, "rad/s": 180 / math.pi, "m/s^2": 1 / 9.80665}


def compatibility_command(
    record: Annotated[str, typer.Argument(help="flight record: .parquet, .csv or SIDPAC .mat")],
    output: Annotated[str | None, typer.Option("-o", "--output",
                                               help="write the corrected record here")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
    strict: opts.Strict = False,
    force: opts.Force = False,
) -> None:
    """Data compatibility: flight path reconstruction of sensor biases, scale factors and
    vane calibration; optionally write the corrected record."""
    check_choice("--format", format, ("table", "json"))
    check_suffix("--output", output, (".parquet", ".csv"))
    check_paths({"RECORD": record}, [Output("--output", output)], force)
    with printed_warnings("compatibility"):
        rec = read_record(record, "compatibility", force=force)
        corrected, est = reconstruct(rec)
        # the checks the standard data reduction applies before it trusts a vane
        # calibration (calm air, physical, identified); -o writes the calibration anyway
        doubts = calibration_doubts(rec, est)
        for text in doubts:
            typer.echo(f"flightid compatibility: warning: vane calibration doubtful: {text}"
                       f"{'; the corrected record applies it anyway' if output else ''} "
                       "(identify applies it only without doubts)", err=True)
    if strict:
        convergence.require(est, "compatibility")
    if output:
        corrected.write(output)
    if format == "json":
        d = est.as_dict()
        d["fit"].pop("cost_history", None)
        d["units"] = est.fit["units"]
        d["calibration_doubts"] = doubts
        print(json.dumps(d, indent=2, default=str))
        return
    console = Console()
    noise = ", ".join(f"{o} {s:.3g}" for o, s in est.fit["noise_std"].items())
    table = Table(title=f"flight path reconstruction: {rec.meta.aircraft or record}  "
                  f"({'converged' if est.fit['converged'] else 'NOT converged'}, "
                  f"std: {est.std_kind.value})")
    for col in ("parameter", "value", "std", "unit", "value (deg, g)"):
        table.add_column(col, justify="left" if col in ("parameter", "unit") else "right")
    for name, value, std in zip(est.names, est.values, est.std, strict=True):
        unit = PARAMETERS[name].unit
        factor = _DISPLAY.get(unit)
        alt = f"{value * factor:.4g} +- {std * factor:.2g}" if factor else ""
        table.add_row(name, f"{value:.6g}", f"{std:.3g}", unit, alt)
    for name, reason in est.unidentifiable.items():
        table.add_row(name, "unidentifiable", "", "", reason, style="yellow")
    console.print(table)
    console.print(f"residual std: {noise}")
    console.print(f"{est.fit['notes'].get('gravity', '')}; {est.fit['reason']}")
    if not convergence.converged(est):
        console.print(convergence.verdict_line(est, "compatibility"), style="bold red")
    if output:
        console.print(f"corrected record written to {output}")
