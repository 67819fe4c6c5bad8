"""``flightid design-compare``: doublet, 2-1-1, 3211, sweep and multisine on the same
aircraft and condition, each over a Monte Carlo study with the same seeds; a table of each
derivative's scatter by design, the designs' flight time and input energy, and
STUDY/design-compare.{png,html} (the work is ``flightid.api.design_compare``)."""

from __future__ import annotations

import json
import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.api import design_compare
from flightid.channels import CONTROLS
from flightid.cli import study_options as opts
from flightid.cli.checks import Output, check_choice, check_number, check_paths, check_study
from flightid.cli.identify import parse_options
from flightid.cli.progress import count_progress
from flightid.scenarios.montecarlo.card_file import card_with_overrides
from flightid.scenarios.montecarlo.design import DESIGNS, EQUAL, Comparison, DesignSettings
from flightid.scenarios.montecarlo.design_report import COST_HEAD, costs_rows
from flightid.units import DEG

SURFACES = tuple(c for c in CONTROLS if c != "throttle")  # the designs move a surface (rad)


def _tables(comparison: Comparison) -> list[Table]:
    costs = Table(title=f"designs (equal {comparison.equal}"
                  + (f": the energy of the {comparison.reference})"
                     if comparison.equal == "energy" else ")"))
    for head in COST_HEAD:
        costs.add_column(head, justify="left" if head == "design" else "right")
    for row in costs_rows(comparison):
        costs.add_row(*(f"{v:.4g}" if isinstance(v, float) else str(v) for v in row))
    scatter, bound = comparison.table("scatter"), comparison.table("mean_bound")
    kinds = list(scatter.columns)
    by = Table(title="scatter of the estimates (mean reported bound) by design; "
               "* smallest scatter")
    by.add_column("derivative", justify="left")
    for k in kinds:
        by.add_column(k, justify="right")
    for name in scatter.index:
        values = scatter.loc[name].astype(float)
        best = values.idxmin() if values.notna().any() else None
        by.add_row(str(name), *(
            "-" if not math.isfinite(float(values[k])) else
            f"{values[k]:.4f} ({bound.loc[name, k]:.4f}){' *' if k == best else ''}"
            for k in kinds))
    return [costs, by]


def design_compare_command(
    card: Annotated[str, typer.Option(
        help="card giving aircraft, condition, sensors, disturbances (its maneuvers are "
             "replaced by each design)")] = "navion-demo",
    n: Annotated[int, typer.Option("-n", help="realizations per design")] = 30,
    output: Annotated[str, typer.Option(
        "-o", "--output", help="study folder (continued when it exists)")] = "design-compare",
    method: opts.Method = "oe",
    model: opts.Model = "lon",
    surface: Annotated[str, typer.Option(help="the surface every design moves")] = "de",
    amplitude_deg: Annotated[float, typer.Option(
        help="peak amplitude (deg) of every design (equal amplitude) or of the reference "
             "(equal energy)")] = 3.0,
    base: Annotated[float, typer.Option(help="pulse base time (s) of the multi-steps")] = 0.4,
    design: Annotated[list[str] | None, typer.Option(
        help=f"design to fly (repeatable; default all: {', '.join(DESIGNS)})")] = None,
    equal: Annotated[str, typer.Option(help="amplitude or energy")] = "amplitude",
    reference: Annotated[str, typer.Option(
        help="with --equal energy: the design whose energy all get")] = "3211",
    option: opts.MethodOptions = None,
    seed: opts.Seed = None,
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    format: opts.Format = "table",
    quiet: opts.Quiet = False,
    set_: opts.Set = None,
    turbulence: opts.Turbulence = None,
    sensors: opts.Sensors = None,
) -> None:
    """Compare input designs by the scatter of the derivatives they give over a Monte
    Carlo (the same seeds for every design), at equal amplitude or equal input energy."""
    check_choice("--format", format, ("table", "json"))
    check_choice("--equal", equal, EQUAL)
    check_choice("--reference", reference, DESIGNS)
    for d in design or ():
        check_choice("--design", d, DESIGNS)
    check_choice("--surface", surface, SURFACES)
    check_number("--amplitude-deg", amplitude_deg, low=0.0, low_open=True, high=90.0,
                 unit="deg")
    check_number("--base", base, low=0.0, low_open=True, high=60.0, unit="s")
    options = parse_options(option or [])
    check_study(n, method, model, options, seed, workers)
    check_paths({"--card": card}, [Output("--output", output, folder=True)])
    card = card_with_overrides(card, output, set_ or (), turbulence, sensors)
    settings = DesignSettings(surface=surface, amplitude=amplitude_deg * DEG, base=base)
    kwargs = dict(card=card, n=n, method=method, model=model,
                  designs=tuple(design or DESIGNS), equal=equal, settings=settings,
                  reference=reference, workers=workers, dask_address=dask, seed=seed,
                  options=options)
    with count_progress("design-compare", show=not quiet) as update:
        progress = ((lambda kind, done, total: update(done, total, f"design-compare {kind}"))
                    if update else None)
        comparison, png, page = design_compare(output, progress=progress, **kwargs)
    if format == "json":
        print(json.dumps(comparison.as_dict(), indent=2, default=str))
        return
    console = Console()
    for table in _tables(comparison):
        console.print(table)
    verdict = comparison.as_dict()["3211_beats_doublet"]
    if verdict is not None:
        wins, total = len(verdict["3211_smaller_scatter"]), verdict["derivatives"]
        console.print(f"3211 smaller scatter than the doublet for {wins} of {total} "
                      "derivatives" + ("" if wins * 2 > total else
                                       " (NOT most: see docs/montecarlo.md for why)"))
    typer.echo(f"wrote {png} and {page}")
