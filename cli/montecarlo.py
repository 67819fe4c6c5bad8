"""``flightid montecarlo`` and ``flightid montecarlo-report``: run, continue or extend a
Monte Carlo accuracy study (``flightid.scenarios.montecarlo``) with a progress bar, and
rebuild its HTML report from the stored rows."""

from __future__ import annotations

import json
import math
import tomllib
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.cli import study_options as opts
from flightid.cli.checks import Output, check_choice, check_paths, check_study
from flightid.cli.identify import parse_options
from flightid.cli.progress import count_progress
from flightid.cli.tables import add_columns
from flightid.scenarios import montecarlo
from flightid.scenarios.montecarlo.card_file import card_with_overrides
from flightid.scenarios.montecarlo.summary import Summary


def summary_table(summary: Summary) -> Table:
    """The per-derivative accuracy as a rich table (its coverage in ``coverage_table``:
    together they would not fit 80 columns)."""
    table = add_columns(Table(title=f"{summary.realizations} realizations, "
                                    f"{summary.failures} failed"),
                        ("derivative", "truth", "bias", "scatter", "mean bound",
                         "scatter/bound"))
    for r in summary.rows:
        table.add_row(r.name, f"{r.truth:.4g}", f"{r.bias:+.3g}", f"{r.scatter:.3g}",
                      f"{r.mean_bound:.3g}", f"{r.ratio:.2f}")
    return table


def coverage_table(summary: Summary) -> Table:
    """Per derivative: the realizations that estimated it, the coverage of its 95 %
    intervals with the 95 % Clopper-Pearson interval of that coverage, and the share
    that found it unidentifiable."""
    table = add_columns(Table(title="coverage of the reported 95 % intervals"),
                        ("derivative", "estimated", "coverage", "95 % interval of it",
                         "unidentifiable"))
    for r in summary.rows:
        table.add_row(r.name, str(r.estimated), _percent(r.coverage),
                      f"{_percent(r.coverage_low)} - {_percent(r.coverage_high)}",
                      _percent(r.unidentifiable))
    return table


def _percent(share: float) -> str:
    return "-" if not math.isfinite(share) else f"{100 * share:.0f} %"


def read_dispersions(path: str) -> list[str]:
    """The ``disperse`` list of strings of a TOML file."""
    with open(path, "rb") as f:
        try:
            data = tomllib.load(f)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"{path}: TOML syntax error: {exc}") from None
    specs = data.get("disperse")
    if not isinstance(specs, list) or not all(isinstance(s, str) for s in specs):
        raise ValueError(f"{path}: expected disperse = [\"EFFECT[.PARAMETER]:WIDTH\", ...], "
                         f"got {specs!r}")
    return specs


def _print(summary: Summary, format: str) -> None:
    if format == "json":
        print(json.dumps(summary.as_dict(), indent=2))
    else:
        console = Console()
        console.print(summary_table(summary))
        console.print(coverage_table(summary))
        for line in summary.warnings():
            console.print(f"warning: {line}")


def montecarlo_command(
    card: Annotated[str, typer.Argument(help="card file or library card name")],
    n: Annotated[int, typer.Option("-n", help="number of realizations")],
    output: Annotated[str, typer.Option(
        "-o", "--output", help="study folder (continued when it exists)")],
    method: opts.Method = "oe",
    model: opts.Model = "lat",
    option: opts.MethodOptions = None,
    seed: opts.Seed = None,
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    dask_scheduler_file: Annotated[str | None, typer.Option(
        help="Dask scheduler file")] = None,
    disperse: Annotated[list[str] | None, typer.Option(
        help="disperse EFFECT[OPTION=VALUE][.PARAMETER]:WIDTH[:normal|uniform] per "
             "realization, e.g. mass_scale:0.05 (repeatable; docs/montecarlo.md)")] = None,
    disperse_file: Annotated[str | None, typer.Option(
        help="TOML file with disperse = [\"mass_scale:0.05\", ...]")] = None,
    format: opts.Format = "table",
    quiet: opts.Quiet = False,
    set_: opts.Set = None,
    turbulence: opts.Turbulence = None,
    sensors: opts.Sensors = None,
    raw: opts.Raw = False,
) -> None:
    """Fly a card N times, identify each flight as identify does (--raw: without the data
    reduction), and summarize bias, scatter and the coverage of the reported bounds; a
    rerun continues the study in -o."""
    check_choice("--format", format, ("table", "json"))
    if dask and dask_scheduler_file:
        raise ValueError("give --dask or --dask-scheduler-file, not both")
    options = parse_options(option or [])
    check_study(n, method, model, options, seed, workers)
    check_paths({"CARD": card, "--disperse-file": disperse_file,
                 "--dask-scheduler-file": dask_scheduler_file},
                [Output("--output", output, folder=True)])
    card = card_with_overrides(card, output, set_ or (), turbulence, sensors)
    specs = [*(read_dispersions(disperse_file) if disperse_file else []), *(disperse or [])]
    kwargs = dict(method=method, model=model, options=options, study_dir=output,
                  workers=workers, dask_address=dask, seed=seed,
                  dask_scheduler_file=dask_scheduler_file, disperse=specs, raw=raw)
    with count_progress(f"Monte Carlo {card}", show=not quiet) as update:
        progress = (lambda done, total: update(done, total)) if update else None
        summary = montecarlo.run(card, n, progress=progress, **kwargs)
    _print(summary, format)
    if format == "table":
        typer.echo(f"wrote {output}/report.html")


def montecarlo_report_command(
    study: Annotated[str, typer.Argument(help="study folder")],
    format: Annotated[str, typer.Option(help="table or json")] = "table",
) -> None:
    """Rebuild STUDY/report.html from the stored results and print the summary."""
    check_choice("--format", format, ("table", "json"))
    check_paths({}, [Output("STUDY", study, folder=True)])
    path, summary = montecarlo.rebuild_report(study)
    _print(summary, format)
    if format == "table":
        typer.echo(f"wrote {path}")
