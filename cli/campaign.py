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


def campaign_command(
    card: Annotated[str, typer.Argument(help="campaign card file or library campaign name")],
    output: Annotated[str, typer.Option(
        "-o", "--output", help="campaign folder (continued when it exists)")],
    workers: opts.Workers = None,
    dask: opts.Dask = None,
    dask_scheduler_file: Annotated[str | None, typer.Option(
        help="Dask scheduler file")] = None,
    quiet: opts.Quiet = False,
) -> None:
    """Fly every test point of a campaign card, identify each, and write per-point
    estimates (Parquet) and an HTML report of the derivatives against the condition."""
    if dask and dask_scheduler_file:
        raise ValueError("give --dask or --dask-scheduler-file, not both")
    if workers is not None and workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    check_paths({"--dask-scheduler-file": dask_scheduler_file},
                [Output("--output", output, folder=True)])
    loaded = campaigns.load_campaign(card)
    with count_progress(f"campaign {loaded.name}", show=not quiet) as update:
        progress = (lambda done, total: update(done, total)) if update else None
        result = campaigns.run(loaded, output, workers=workers, dask_address=dask,
                               dask_scheduler_file=dask_scheduler_file, progress=progress)
    Console().print(points_table(result.scores))
    typer.echo(f"wrote {result.folder / campaigns.ESTIMATES} and {result.report}")
