"""The effect catalogue rendered: as plain data (``flightid effects --format json``) and as
the Markdown table of docs/effects.md.
"""

from __future__ import annotations

import math
from typing import Any

from flightid.sim.effects.base import ExternalImplementation
from flightid.sim.effects.catalogue import CATALOGUE
from flightid.sim.effects.schema import ActsOn, number_text


def listing(where: ActsOn | str | None = None) -> list[dict[str, Any]]:
    """The catalogue as plain, JSON-safe data (non-finite numbers as "inf"/"-inf").

    Parameters
    ----------
    where : ActsOn or str, optional
        Only the entries acting there; default all.

    Returns
    -------
    list of dict
        One dict per entry: name, acts_on, description, parameters, options, changes, etc.
    """
    entries = CATALOGUE.acting_on(ActsOn(where)) if where else list(CATALOGUE.values())
    return [{
        "name": e.name,
        "acts_on": str(e.acts_on),
        "description": e.description,
        "parameters": [{
            "name": p.name, "unit": p.unit, "meaning": p.meaning,
            "default": _json(p.default), "neutral": _json(p.neutral),
            "low": _json(p.low), "high": _json(p.high), "range": p.range_text(),
            "sizes": p.sizes,
        } for p in e.parameters],
        "options": [{"name": o.name, "choices": list(o.choices), "default": o.default,
                     "meaning": o.meaning} for o in e.options],
        "changes": list(e.changes),
        "sized_for_channel": e.channel,
        "implementation": e.implementation_name(),
        "parameter_mapping": (e.implementation.mapping()
                              if isinstance(e.implementation, ExternalImplementation) else {}),
        "inject": e.how(),
    } for e in entries]


def markdown_table() -> str:
    """The catalogue as a Markdown table (docs/effects.md holds it; a test keeps it current).

    Returns
    -------
    str
        The table, newline-terminated.
    """
    rows = ["| name | acts on | parameters: default (blind tests), allowed range | "
            "description | injected by |",
            "|---|---|---|---|---|"]
    for e in CATALOGUE.values():
        params = []
        for p in e.parameters:
            unit = "" if p.unit == "1" else f" {p.unit}"
            params.append(f"`{p.name}` = {number_text(p.default)}{unit}, {p.range_text()}")
        params += [f"`{o.name}`: {', '.join(repr(c) for c in o.choices)}" for o in e.options]
        rows.append(f"| `{e.name}` | {e.acts_on} | {'<br>'.join(params)} | {e.description} "
                    f"| `{e.how()}` |")
    return "\n".join(rows) + "\n"


def _json(x: float | None) -> float | str | None:
    if x is None or math.isfinite(x):
        return x
    return "inf" if x > 0 else "-inf"
