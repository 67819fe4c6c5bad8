"""``flightid campaign CARD -o DIR``: fly and identify every test point of a campaign card
(``flightid.scenarios.campaign``) with a progress bar, locally or on Dask; a rerun
continues in DIR. Prints the share of estimates within 3 sigma of the truth per point."""

from __future__ import annotations

import math
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from flightid.cli import study_options as opts
from flightid.cli.checks import Output, check_paths
from flightid.cli.progress import count_progress
from flightid.cli.tables import add_columns
from flightid.scenarios import campaign as campaigns
from flightid.scenarios.campaign.report import N_SIGMA, PointScore


def points_table(scores: list[PointScore]) -> Table:
    """Per test point: condition, trim alpha, estimated, within 3 sigma, the worst."""
    table = add_columns(Table(title="test points"),
                        ("point", "altitude m", "speed m/s", "alpha deg", "estimated",
                         f"within {N_SIGMA:g} sigma", "worst / failure"))
    for s in scores:
        share = "-" if math.isnan(s.share) else f"{s.within} ({100 * s.share:.0f} %)"
        table.add_row(str(s.index), f"{s.altitude:g}", f"{s.speed:g}",
                      f"{math.degrees(s.alpha):.2f}", str(s.estimated), share,
                      s.worst or s.failed)
    return table


def update_table(update: dict) -> Table:
    """The corrections kept and the held-out gap per axis, before and after."""
    table = add_columns(Table(title="database update"), ("derivative", "form", "shift",
                                                         "scale", "slope per x unit"))
    for c in update["corrections"]:
        if c["form"] != "none":
            table.add_row(c["name"], c["form"], f"{c['shift']:+.4g}", f"{c['scale']:.4g}",
                          f"{c['slope']:+.4g}")
    for axis, shrink in update["shrink"].items():
        if update["mean"]:
            m, above = update["mean"], update["shrink_above_floor"][axis]
            table.add_row(f"held-out gap {axis}", f"floor {m['floor'][axis]:.4f}",
                          f"{m['before'][axis]:.4f} before", f"{m['after'][axis]:.4f} after",
                          f"{100 * shrink:.0f} % smaller ({100 * above:.0f} % above floor)")
    for name, g in update["derivative_gap"].items():
        table.add_row(f"held-out {name}", "RMS error", f"{g['model']:.4g} before",
                      f"{g['updated']:.4g} after", "")
    return table


def campaign_command(
    card: Annotated[str, typer.Argument(help="campaign card file or library campaign name")],
    output: Annotated[str, typer.Option(
        "-o", "--output", help="campaign folder (continued when it exists)")],
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    dask_scheduler_file: Annotated[str | None, typer.Option(
        help="Dask scheduler file")] = None,
    quiet: opts.Quiet = False,
    update_aircraft: Annotated[str | None, typer.Option(
        help="write the model aircraft with its tables relocated to the flight points in "
             "this folder, and report the gap on the held-out points before and after")]
        = None,
) -> None:
    """Fly every test point of a campaign card, identify each, and write per-point
    estimates (Parquet) and an HTML report of the derivatives against the condition."""
    if dask and dask_scheduler_file:
        raise ValueError("give --dask or --dask-scheduler-file, not both")
    if workers is not None and workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    check_paths({"--dask-scheduler-file": dask_scheduler_file},
                [Output("--output", output, folder=True),
                 Output("--update-aircraft", update_aircraft, folder=True)])
    loaded = campaigns.load_campaign(card)
    with count_progress(f"campaign {loaded.name}", show=not quiet) as update:
        progress = (lambda done, total: update(done, total)) if update else None
        result = campaigns.run(loaded, output, workers=workers, dask_address=dask,
                               dask_scheduler_file=dask_scheduler_file, progress=progress,
                               update_aircraft=update_aircraft)
    Console().print(points_table(result.scores))
    if result.update is not None:
        Console().print(update_table(result.update))
        typer.echo(f"wrote {result.aircraft}")
    if result.global_model is not None:
        typer.echo(f"wrote {result.folder / campaigns.GLOBAL} (one model over points "
                   f"{', '.join(map(str, result.global_model['points']))})")
    typer.echo(f"wrote {result.folder / campaigns.ESTIMATES} and {result.report}")
