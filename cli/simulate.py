"""``flightid simulate``: fly a flight card and write its records (printing only; the work
is ``flightid.scenarios.simulate``, the exit codes are the policy of ``flightid.cli.app``)."""

from __future__ import annotations

from typing import Annotated

import typer

from flightid.cli.progress import flight_progress
from flightid.scenarios.cards import load_card
from flightid.scenarios.simulate import list_cards, simulate


def simulate_command(
    card: Annotated[str | None, typer.Argument(help="card file or library card name")] = None,
    output: Annotated[str | None, typer.Option("-o", "--output",
                                               help="measured record (.parquet or .csv)")] = None,
    truth: Annotated[str | None, typer.Option(help="also write the truth record here")] = None,
    plot: Annotated[str | None, typer.Option(help="write a PNG of inputs and responses")] = None,
    seed: Annotated[int | None, typer.Option(help="random seed (default: the card's)")] = None,
    list_cards_: Annotated[bool, typer.Option("--list", help="list the library cards")] = False,
) -> None:
    """Fly a flight card (file or library name) and write the measured record."""
    if list_cards_:
        for name, text in list_cards():
            typer.echo(f"{name:32s} {text}")
        return
    if card is None or output is None:
        raise typer.BadParameter("give a CARD and -o/--output (or --list)")
    # errors (CardError: exit 2; TrimError, DepartureError: exit 3) are the app's policy
    loaded = load_card(card)
    with flight_progress(f"flying {loaded.name}", loaded.duration) as progress:
        measured, _ = simulate(loaded, output, truth, plot, seed, progress=progress)
    typer.echo(f"wrote {output}: {len(measured)} samples, {measured.time[-1]:.2f} s, "
               f"{len(measured.channels)} channels at {measured.meta.sample_rate:g} Hz")
    for extra in (truth, plot):
        if extra:
            typer.echo(f"wrote {extra}")
