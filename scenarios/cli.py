"""The ``flightid`` command line: thin wiring from commands to library functions."""

from __future__ import annotations

import typer

app = typer.Typer(
    help="flightid: aircraft system identification testbed (JSBSim truth flights, "
    "flight-test inputs, identification scored against known derivatives).",
    no_args_is_help=True,
    add_completion=False,
)


@app.callback()
def _main() -> None:
    """flightid: aircraft system identification testbed."""


@app.command()
def version() -> None:
    """Print the flightid version."""
    from flightid import __version__

    typer.echo(__version__)


if __name__ == "__main__":
    app()
