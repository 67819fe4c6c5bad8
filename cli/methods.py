"""``flightid methods``: every registered identification method with its options."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from flightid.api import methods
from flightid.cli.checks import check_choice


def methods_command(
    method: Annotated[str | None, typer.Argument(help="show only this method id")] = None,
    format: Annotated[str, typer.Option(help="table or json")] = "table",
) -> None:
    """List the identification methods: id, what it does, its models and every option
    with its type, default and meaning."""
    check_choice("--format", format, ("table", "json"))
    found = methods()
    if method is not None and method not in found:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(found)}")
    chosen = [found[method]] if method else list(found.values())
    if format == "json":
        print(json.dumps({m.id: {"name": m.name, "summary": m.summary,
                                 "reference": m.reference, "models": list(m.models),
                                 "default_model": m.default_model,
                                 "options": m.describe()} for m in chosen}, indent=2))
        return
    console = Console()
    for m in chosen:
        table = Table(title=escape(f"{m.id}: {m.name}"), caption=escape(
                          f"{m.summary}. Models: {', '.join(m.models)} (default "
                          f"{m.default_model}). {m.reference}"),
                      title_justify="left", caption_justify="left")
        for col in ("option", "type", "default", "meaning"):
            table.add_column(col, overflow="fold")
        for row in m.describe():
            table.add_row(*(escape(row[k]) for k in ("name", "type", "default", "help")))
        console.print(table)
