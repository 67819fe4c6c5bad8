"""Options shared by several commands (the Monte Carlo ones, ``montecarlo`` and
``design-compare``; ``--strict`` and ``--force`` of the commands that read a record): one
declaration each, so that their help and names stay the same."""

from __future__ import annotations

from typing import Annotated

import typer

Method = Annotated[str, typer.Option(help="method id (flightid methods)")]
Model = Annotated[str, typer.Option(help="model (as for flightid identify)")]
MethodOptions = Annotated[list[str] | None, typer.Option(
    help="method option KEY=VALUE (repeatable)")]
Seed = Annotated[int | None, typer.Option(
    help="base seed of the realizations (default: the card's)")]
Workers = Annotated[int | None, typer.Option(
    help="local worker processes (default: one per CPU)")]
Dask = Annotated[str | None, typer.Option(
    "--dask", help="Dask scheduler address, e.g. tcp://host:8786")]
Format = Annotated[str, typer.Option(help="table or json")]
Quiet = Annotated[bool, typer.Option(help="no progress bar")]
# card overrides (flightid.scenarios.cards.override), shared with `flightid simulate`
Set = Annotated[list[str] | None, typer.Option(
    "--set", help="override a card field KEY=VALUE by its TOML path, e.g. condition.speed=60 "
                  "or sensors.drop=vanes,lever_arm (repeatable)")]
Turbulence = Annotated[str | None, typer.Option(
    help="replace the card's turbulence: none, light or moderate")]
Sensors = Annotated[str | None, typer.Option(
    help="replace the card's sensors by a built-in suite: research, hobby or ideal")]
# the commands that read a record and fit it (identify, compatibility, gap, ...)
Strict = Annotated[bool, typer.Option(
    "--strict", help="exit 4 when a fit does not converge (default: a warning and 'not "
                     "converged' in the verdict line, exit 0)")]
Force = Annotated[bool, typer.Option(
    "--force", help="run when the memory estimate exceeds what is available, and write the "
                    "outputs over an existing file of another kind")]
# identify and montecarlo: the standard data reduction is skipped
Raw = Annotated[bool, typer.Option(
    "--raw", help="skip the standard data reduction (accelerometers and vanes to the CG, "
                  "vane scale and bias; docs/record.md)")]
