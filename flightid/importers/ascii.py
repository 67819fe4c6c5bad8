"""Delimited text flight data (CSV, semicolon or whitespace separated ASCII) into a
FlightRecord: a header row of column names, an optional units row under it (``S RAD PA
M/S ...``) or units in the names (``alpha [deg]``), then one row of numbers per sample.

Each column becomes the channel the :class:`~flightid.importers.mapping.ColumnMap` maps it
to (a column already named as a canonical channel needs no entry), converted from its
unit (the map's, else the file's) to the channel's SI unit (``flightid.units.to_si``); a
column without a unit is taken as already in SI and said so. Columns that are not mapped
are kept under their own names, converted to SI where their unit is known, else as they
are with their unit recorded. Lines starting with ``#`` or ``%`` before the header are
comments. A last row cut short (a file truncated while it was written) is dropped and
said so; any other row with a wrong number of fields or a value that is not a number is
refused, naming its line and column.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from flightid.channels import CHANNELS
from flightid.flight_record import FlightRecord, RecordMeta, check_samples
from flightid.importers.mapping import TIME, ColumnMap, valid_channels
from flightid.units import UNIT_NAMES, to_si, unit_key

COMMENT = ("#", "%")
TIME_NAMES = ("time", "t")  # a column of this name (any case) is the time without a map
_NAME_UNIT = re.compile(r"^(.*?)\s*[\[(]([^\])]*)[\])]\s*$")  # 'alpha [deg]', 'V (kt)'
# channels the reference condition of a perturbation model is taken from (record means)
CONDITION_CHANNELS = ("V", "h", "alpha", "beta", "qbar", "rho", "mass")


def _split(line: str, sep: str | None) -> list[str]:
    return [f.strip() for f in (line.split(sep) if sep else line.split())]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _lines(path: Path) -> list[tuple[int, str]]:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a UTF-8 text file (byte {exc.start}); export the "
                         "data as delimited text") from None
    return [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]


def read_delimited(path: str | Path, column_map: ColumnMap | None = None) -> FlightRecord:
    """Read a delimited text file into a FlightRecord in SI units (module docstring).

    Parameters
    ----------
    path : the text file.
    column_map : file column -> channel and unit overrides (default: none; columns named
        as canonical channels and a ``time``/``t`` column are taken as they are).

    Returns
    -------
    FlightRecord whose ``meta.extra['import']`` says, per column, the channel, the unit
    read and the factor applied, the columns kept under their own names and the rows
    dropped; ``meta.condition`` holds the record means of V, h, alpha, beta, qbar, rho
    and mass (the reference of perturbation models, as for a SIDPAC record).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    cmap = column_map or ColumnMap()
    lines = _lines(path)
    while lines and lines[0][1].lstrip().startswith(COMMENT):
        lines.pop(0)
    if len(lines) < 2:
        raise ValueError(f"{path}: no header row and data rows (a delimited text file has "
                         "a row of column names, then one row of numbers per sample)")
    header = lines[0][1]
    sep = "," if "," in header else ";" if ";" in header else None
    names, name_units = [], {}
    for field in _split(header, sep):
        match = _NAME_UNIT.match(field)
        name = match.group(1).strip() if match else field
        if match:
            name_units[name] = match.group(2).strip()
        names.append(name)
    if len(set(names)) != len(names):
        twice = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"{path}: column name(s) {', '.join(twice)} appear twice in the "
                         "header")
    body = lines[1:]
    units_row: dict[str, str] = {}
    first = _split(body[0][1], sep)
    if not any(_is_number(f) for f in first):  # a units row
        if len(first) != len(names):
            raise ValueError(f"{path} line {body[0][0]}: the units row has {len(first)} "
                             f"fields, the header {len(names)}")
        units_row = dict(zip(names, first, strict=True))
        body = body[1:]
    missing = sorted((set(cmap.columns) | set(cmap.units)) - set(names))
    if missing:
        raise ValueError(f"{path}: the map names column(s) {', '.join(missing)} that the file "
                         f"does not have; its columns: {', '.join(names)}")
    rows, dropped = _rows(path, body, sep, len(names))
    if len(rows) < 2:
        raise ValueError(f"{path}: fewer than two whole data rows")
    values = _numbers(path, names, rows, body)
    return _record(path, names, values, {**name_units, **units_row}, cmap, dropped)


def _rows(path: Path, body: list[tuple[int, str]], sep: str | None, width: int
          ) -> tuple[list[list[str]], list[str]]:
    rows, dropped = [], []
    for k, (number, line) in enumerate(body):
        fields = _split(line, sep)
        if len(fields) == width:
            rows.append(fields)
            continue
        if k == len(body) - 1 and len(fields) < width:
            dropped.append(f"line {number}: the last row has {len(fields)} of {width} fields "
                           "(the file was cut while it was written); dropped")
            continue
        raise ValueError(f"{path} line {number}: {len(fields)} fields, the header has "
                         f"{width}; the file is damaged or the delimiter is not one of ',', "
                         "';' and spaces")
    return rows, dropped


def _numbers(path: Path, names: list[str], rows: list[list[str]],
             body: list[tuple[int, str]]) -> dict[str, np.ndarray]:
    out = {}
    for j, name in enumerate(names):
        column = [r[j] for r in rows]
        try:
            out[name] = np.array(column, dtype=float)
        except ValueError:
            i = next(i for i, v in enumerate(column) if not _is_number(v))
            line = body[i][0]  # only the last row is ever dropped
            raise ValueError(f"{path}: column {name!r} has a value that is not a number "
                             f"({column[i][:20]!r} on line {line})") from None
    return out


def _record(path: Path, names: list[str], values: dict[str, np.ndarray],
            file_units: dict[str, str], cmap: ColumnMap, dropped: list[str]) -> FlightRecord:
    mapped = dict(cmap.columns)
    for name in names:  # a column already named as a channel (or time) needs no entry
        if name not in mapped and name in valid_channels() and name not in mapped.values():
            mapped[name] = name
    if TIME not in mapped.values():
        found = [n for n in names if n.lower() in TIME_NAMES and n not in mapped]
        if not found:
            raise ValueError(f"{path}: no time column: map one to 'time' (e.g. --map T=time); "
                             f"columns: {', '.join(names)}")
        mapped[found[0]] = TIME
    notes: list[str] = []
    columns: dict[str, dict[str, Any]] = {}
    channels: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    time = None
    for name in names:
        unit_text = cmap.units.get(name, file_units.get(name))
        target = mapped.get(name)
        if target is not None:
            si = "s" if target == TIME else CHANNELS[target].unit
            if unit_text is None:
                factor = 1.0
                notes.append(f"column {name} ({target}) has no unit: taken as {si}")
            else:
                try:
                    factor = to_si(unit_text, si)[1]
                except (KeyError, ValueError) as exc:
                    raise ValueError(f"{path}: column {name} ({target}): "
                                     f"{exc.args[0]}") from None
            data = values[name] * factor
            if target == TIME:
                time = data
            else:
                channels[target] = data
            columns[name] = {"channel": target, "unit": unit_text, "factor": factor}
            continue
        # kept under its own name: in SI where its unit is known
        if unit_text is not None and unit_key(unit_text) in UNIT_NAMES:
            si, factor = to_si(unit_text)
        else:
            si, factor = (unit_text or "unknown"), 1.0
            notes.append(f"column {name} kept as it is (unit {unit_text or 'not given'})")
        if name in channels or name in CHANNELS:
            raise ValueError(f"{path}: column {name!r} is named as a flightid channel that "
                             "another column is mapped to; map it to a channel or rename it")
        channels[name] = values[name] * factor
        units[name] = si
        columns[name] = {"channel": None, "unit": unit_text, "factor": factor, "kept_as": si}
    assert time is not None
    check_samples(str(path), time, channels)
    condition: dict[str, Any] = {k: float(np.mean(channels[k])) for k in CONDITION_CHANNELS
                                 if k in channels}
    if condition:
        condition["note"] = ("means over the record (SI units), the reference of "
                             "perturbation models")
    step = float(np.median(np.diff(time)))
    meta = RecordMeta(
        condition=condition, sample_rate=1.0 / step if step > 0 else 0.0,
        provenance=f"delimited text {path.name} imported by flightid.importers.ascii",
        units=units,
        extra={"import": {"format": "delimited text", "file": path.name, "columns": columns,
                          "kept": [n for n, c in columns.items() if c["channel"] is None],
                          "dropped": dropped, "notes": notes}},
    )
    return FlightRecord(time, channels, meta)
