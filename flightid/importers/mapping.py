"""The column map of an import: which column of a file is which flightid channel, and in
which unit, given as ``--map COLUMN=channel,...`` text or a TOML mapping file::

    [columns]            # file column = flightid channel ("time" for the time column)
    T = "time"
    ALFCG = "alpha"
    TASCG = "V"

    [units]              # optional: file column = unit, over the file's own units row
    ALFCG = "deg"

A channel must be canonical (``flightid.channels``) or ``time``; anything else is refused
naming the valid names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from flightid.channels import CHANNELS
from flightid.files import read_toml
from flightid.units import UNIT_NAMES, unit_key

TIME = "time"


@dataclass
class ColumnMap:
    """File column -> channel, and file column -> unit name (overriding the file's)."""

    columns: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    def merged(self, other: ColumnMap) -> ColumnMap:
        """This map with ``other``'s entries added (``other`` wins on a column given in
        both)."""
        return ColumnMap({**self.columns, **other.columns}, {**self.units, **other.units})


def valid_channels() -> list[str]:
    """The names a column may be mapped to: ``time`` and the canonical channels.

    Returns
    -------
    list of str
        ``time`` followed by the canonical channel names.
    """
    return [TIME, *CHANNELS]


def check_channel(channel: str, where: str) -> str:
    """``channel`` if it is ``time`` or canonical, else a ValueError naming the valid names.

    Parameters
    ----------
    channel : str
        Channel name to check.
    where : str
        Says which entry of which map, for the message.

    Returns
    -------
    str
        ``channel``.
    """
    if channel not in valid_channels():
        raise ValueError(f"{where}: {channel!r} is not a flightid channel; valid channels: "
                         f"{', '.join(valid_channels())}")
    return channel


def check_unit(unit: str, where: str) -> str:
    """``unit`` if :data:`flightid.units.UNIT_NAMES` knows it, else a ValueError naming them.

    Parameters
    ----------
    unit : str
        Unit name to check.
    where : str
        Says which entry of which map, for the message.

    Returns
    -------
    str
        ``unit``.
    """
    if unit_key(unit) not in UNIT_NAMES:
        raise ValueError(f"{where}: unknown unit {unit!r}; known units: "
                         f"{', '.join(k for k in UNIT_NAMES if k)}")
    return unit


def _pairs(text: str, option: str) -> list[tuple[str, str]]:
    pairs = []
    for item in (p.strip() for p in text.split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"{option} {item!r}: write COLUMN=VALUE (e.g. ALFCG=alpha)")
        pairs.append((key.strip(), value.strip()))
    return pairs


def parse_map(texts: list[str], unit_texts: list[str] | None = None) -> ColumnMap:
    """A ColumnMap from ``--map`` and ``--unit`` texts; unknown channels and units are refused.

    Parameters
    ----------
    texts : list of str
        ``--map`` texts, e.g. 'ALFCG=alpha,TASCG=V' (repeatable).
    unit_texts : list of str, optional
        ``--unit`` texts, e.g. 'ALFCG=deg'.

    Returns
    -------
    ColumnMap
        Column to channel and column to unit maps.
    """
    out = ColumnMap()
    for text in texts:
        for column, channel in _pairs(text, "--map"):
            out.columns[column] = check_channel(channel, f"--map {column}={channel}")
    for text in unit_texts or []:
        for column, unit in _pairs(text, "--unit"):
            out.units[column] = check_unit(unit, f"--unit {column}={unit}")
    _check_unique(out)
    return out


def read_map(path: str | Path) -> ColumnMap:
    """A ColumnMap from a TOML mapping file (format in the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The mapping file, with [columns] and [units] tables.

    Returns
    -------
    ColumnMap
        Column to channel and column to unit maps.
    """
    path = Path(path)
    data = read_toml(path, "mapping file", "TOML mapping file")
    unknown = sorted(set(data) - {"columns", "units"})
    if unknown:
        raise ValueError(f"{path}: unknown table(s) {', '.join(unknown)}; a mapping file has "
                         "[columns] and [units]")
    out = ColumnMap()
    for key in ("columns", "units"):
        table = data.get(key, {})
        if not isinstance(table, dict) or not all(isinstance(v, str) for v in table.values()):
            raise ValueError(f"{path}: [{key}] must hold COLUMN = \"text\" entries")
    for column, channel in data.get("columns", {}).items():
        out.columns[column] = check_channel(channel, f"{path} [columns] {column}")
    for column, unit in data.get("units", {}).items():
        out.units[column] = check_unit(unit, f"{path} [units] {column}")
    _check_unique(out)
    return out


def _check_unique(cmap: ColumnMap) -> None:
    seen: dict[str, str] = {}
    for column, channel in cmap.columns.items():
        if channel in seen:
            raise ValueError(f"columns {seen[channel]!r} and {column!r} are both mapped to "
                             f"{channel!r}; map one column to each channel")
        seen[channel] = column
