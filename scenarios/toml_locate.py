"""Find the line of a field in a TOML text, so errors can name file, line and field.

``tomllib`` parses but forgets positions; this scans the text once, tracking table
headers (``[a.b]``) and arrays of tables (``[[a]]``), and maps each key path, e.g.
``("maneuver", 2, "amplitude_deg")``, to its 1-based line number.
"""

from __future__ import annotations

import re

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"""^\s*("[^"]*"|'[^']*'|[A-Za-z0-9_\-.]+)\s*=""")


def _split_dotted(key: str) -> list[str]:
    parts = re.findall(r"""\"[^\"]*\"|'[^']*'|[^.]+""", key)
    return [p.strip().strip("\"'") for p in parts]


def line_index(text: str) -> dict[tuple, int]:
    """Map each key path (strings and array-of-tables indices) to its line (1-based).

    Parameters
    ----------
    text : str
        Text of a TOML file.

    Returns
    -------
    dict[tuple, int]
        Key path (table names, keys and array-of-tables indices) -> first line where it
        appears, 1-based.
    """
    index: dict[tuple, int] = {}
    counts: dict[tuple, int] = {}
    prefix: tuple = ()
    for lineno, line in enumerate(text.splitlines(), start=1):
        m = _HEADER.match(line)
        if m:
            names = tuple(_split_dotted(m.group(2)))
            if m.group(1) == "[[":
                n = counts.get(names, -1) + 1
                counts[names] = n
                prefix = (*_resolve(names[:-1], counts), names[-1], n)
            else:
                prefix = _resolve(names, counts)
            index.setdefault(prefix, lineno)
            continue
        k = _KEY.match(line)
        if k:
            path = (*prefix, *_split_dotted(k.group(1)))
            index.setdefault(path, lineno)
    return index


def _resolve(names: tuple, counts: dict[tuple, int]) -> tuple:
    """Insert array-of-tables indices into a header path ([maneuver.options] -> maneuver, n)."""
    out: list = []
    for i in range(len(names)):
        out.append(names[i])
        if names[: i + 1] in counts:
            out.append(counts[names[: i + 1]])
    return tuple(out)


def line_of(index: dict[tuple, int], path: tuple) -> int | None:
    """Line of ``path`` or of its nearest enclosing table; None if nothing matches.

    Parameters
    ----------
    index : dict[tuple, int]
        Key path -> line, as made by :func:`line_index`.
    path : tuple
        Key path to look up.

    Returns
    -------
    int or None
        Line number, 1-based, or None.
    """
    path = tuple(path)
    while path:
        if path in index:
            return index[path]
        path = path[:-1]
    return None
