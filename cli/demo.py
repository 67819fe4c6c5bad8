"""``flightid demo``: the main job with a progress bar and the scored tables."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from flightid.cli.checks import MAX_SEED, Output, check_count, check_paths, printed_warnings
from flightid.cli.progress import flight_progress
from flightid.cli.tables import estimate_table, print_score
from flightid.scenarios import demo


def demo_command(
    card: Annotated[str, typer.Option(help="library card name or TOML path")] = "navion-demo",
    seed: Annotated[int | None, typer.Option(help="random seed (default: the card's)")] = None,
    report: Annotated[str, typer.Option(help="HTML report to write")] = "flightid-demo.html",
    force: Annotated[bool, typer.Option(
        "--force", help="write --report over an existing file of another kind")] = False,
) -> None:
    """The main job: fly the built-in Navion card, identify by output error, score, report."""
    if seed is not None:
        check_count("--seed", seed, low=0, high=MAX_SEED)
    plot = Path(report).with_suffix(".flight.png") if report.strip() else None
    check_paths({"--card": card}, [Output("--report", report, "html"),
                                   Output("--report (its plot)", plot, "png")], force)
    console = Console()
    with printed_warnings("demo"), flight_progress("flying the card", 1.0) as progress:
        result = demo.run(card, seed, report, progress=progress)
    for est, scored in zip(result.estimates, result.scores, strict=True):
        console.print(estimate_table(est))
        print_score(scored, console)
    if result.report is not None:
        console.print(f"report: {result.report}")
