"""``flightid simulate``: fly a flight card and write its records (printing only; the work
is ``flightid.scenarios.simulate``, the exit codes are the policy of ``flightid.cli.app``)."""

from __future__ import annotations

import warnings
from typing import Annotated

import typer

from flightid.channels import CHANNELS
from flightid.cli import study_options as opts
from flightid.cli.checks import (
    MAX_SEED,
    SIZE_LIMIT,
    Output,
    check_count,
    check_paths,
    check_rate,
    check_size,
    check_suffix,
    estimated_bytes,
)
from flightid.cli.progress import flight_progress
from flightid.scenarios.cards import load_card, overridden_card
from flightid.scenarios.simulate import ClippedInputWarning, list_cards, simulate

RECORD_SUFFIXES = (".parquet", ".csv")


def simulate_command(
    card: Annotated[str | None, typer.Argument(help="card file or library card name")] = None,
    output: Annotated[str | None, typer.Option("-o", "--output",
                                               help="measured record (.parquet or .csv)")] = None,
    truth: Annotated[str | None, typer.Option(help="also write the truth record here")] = None,
    plot: Annotated[str | None, typer.Option(help="write a PNG of inputs and responses")] = None,
    seed: Annotated[int | None, typer.Option(help="random seed (default: the card's)")] = None,
    list_cards_: Annotated[bool, typer.Option("--list", help="list the library cards")] = False,
    force: Annotated[bool, typer.Option(
        "--force", help=f"write even above {SIZE_LIMIT / 1e9:g} GB, and over an existing "
                        "file of another kind")] = False,
    set_: opts.Set = None,
    turbulence: opts.Turbulence = None,
    sensors: opts.Sensors = None,
) -> None:
    """Fly a flight card (file or library name) and write the measured record."""
    if list_cards_:
        for name, text in list_cards():
            typer.echo(f"{name:32s} {text}")
        return
    if card is None or output is None:
        raise typer.BadParameter("give a CARD and -o/--output (or --list)")
    # errors (CardError: exit 2; TrimError, DepartureError: exit 3) are the app's policy
    for option, path, kinds in (("--output", output, RECORD_SUFFIXES),
                                ("--truth", truth, RECORD_SUFFIXES),
                                ("--plot", plot, (".png", ".svg", ".pdf"))):
        check_suffix(option, path, kinds)
    check_paths({"CARD": card}, [Output("--output", output), Output("--truth", truth),
                                 Output("--plot", plot)], force)
    if seed is not None:
        check_count("--seed", seed, low=0, high=MAX_SEED)
    loaded = overridden_card(load_card(card), set_ or (), turbulence, sensors)
    check_rate(f"card {loaded.name}: rate", loaded.rate, loaded.duration)
    samples = loaded.duration * loaded.rate + 1
    files = 2 if truth else 1
    check_size(f"card {loaded.name} ({loaded.duration:g} s at {loaded.rate:g} Hz)",
               files * estimated_bytes(samples, len(CHANNELS)), force)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ClippedInputWarning)
        with flight_progress(f"flying {loaded.name}", loaded.duration) as progress:
            measured, _ = simulate(loaded, output, truth, plot, seed, progress=progress)
    for w in caught:
        if issubclass(w.category, ClippedInputWarning):
            typer.echo(f"flightid simulate: warning: {w.message}", err=True)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    typer.echo(f"wrote {output}: {len(measured)} samples, {measured.time[-1]:.2f} s, "
               f"{len(measured.channels)} channels at {measured.meta.sample_rate:g} Hz")
    for extra in (truth, plot):
        if extra:
            typer.echo(f"wrote {extra}")
