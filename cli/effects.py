"""``flightid effects``: the effect catalogue as a table or JSON (printing only; the listing
is ``flightid.sim.effects.catalogue.listing``)."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from flightid.cli.checks import check_choice
from flightid.sim.effects.catalogue import ActsOn
from flightid.sim.effects.listing import listing, markdown_table


def _parameters(entry: dict) -> str:
    lines = []
    for p in entry["parameters"]:
        unit = "" if p["unit"] == "1" else f" {p['unit']}"
        bounds = "" if p["range"] == "(-inf, inf)" else f"  {p['range']}"
        lines.append(f"{p['name']} = {_fmt(p['default'])}{unit}{bounds}")
    lines += [f"{o['name']}: {' | '.join(c or '-' for c in o['choices'])}"
              for o in entry["options"]]
    return "\n".join(lines)


def _fmt(x: float | str) -> str:
    return x if isinstance(x, str) else f"{x:g}"


def effects_command(
    acts_on: Annotated[str | None, typer.Option(
        "--acts-on", help=f"only effects acting on: {', '.join(a.value for a in ActsOn)}"
    )] = None,
    format: Annotated[str, typer.Option(
        help="table, json, or markdown (the table of docs/effects.md)")] = "table",
) -> None:
    """The effect catalogue: every injectable effect, where it acts, its parameters (default
    magnitude for blind tests and allowed range) and what it does."""
    check_choice("--format", format, ("table", "json", "markdown"))
    if acts_on is not None and acts_on not in {a.value for a in ActsOn}:
        raise ValueError(f"--acts-on: unknown {acts_on!r}; one of "
                         f"{', '.join(a.value for a in ActsOn)}")
    if format == "markdown":
        if acts_on is not None:
            raise ValueError("--format markdown lists the whole catalogue; drop --acts-on")
        print(markdown_table(), end="")
        return
    entries = listing(acts_on)
    if format == "json":
        print(json.dumps(entries, indent=2))
        return
    table = Table(title=escape("effect catalogue: parameters at their default magnitude for "
                               "blind tests, with the allowed range; [ch] = the unit of the "
                               "channel a sensor effect is on (defaults sized for q, rad/s)"),
                  show_lines=True)
    for col in ("name", "acts on", "parameters (default, range)", "description"):
        table.add_column(col, overflow="fold")
    for e in entries:
        table.add_row(e["name"], e["acts_on"], escape(_parameters(e)), escape(e["description"]))
    Console().print(table)
