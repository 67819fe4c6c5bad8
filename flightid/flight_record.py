"""The flight record type: time (s), named channels in SI units, and metadata, with its
own lossless file formats (Parquet and CSV, written by :meth:`FlightRecord.write`, read
back by :func:`read_parquet` and :func:`read_csv`).

Import it as ``flightid.record`` (which re-exports everything here and adds ``read``, the
reader of every format including SIDPAC .mat): the type lives in this module, below
``flightid.sidpac``, so that the SIDPAC reader can build records and ``flightid.record``
can dispatch to it without the two importing each other.

Channel names and units are the canonical ones of ``flightid.channels``; a channel outside
that table must carry its unit in ``meta.units``. Units are converted once, at the
boundary (readers, simulator).
"""

from __future__ import annotations

import json
import zlib
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from flightid.channels import CHANNELS
from flightid.files import atomic_path

FORMAT_VERSION = 1
_CSV_MARK = "# flightid-record "
# a Parquet record carries a CRC-32 of every block of this many rows of every column under
# this schema key, so damage that still decodes (zeroed or flipped bytes inside a data
# page) is found on read and named by column and rows
_CRC_KEY = b"flightid-crc32"
CRC_BLOCK = 1024


@dataclass(frozen=True)
class Reference:
    """Reference geometry for nondimensional coefficients: area (m^2), span, chord (m)."""

    area: float
    span: float
    chord: float


@dataclass
class RecordMeta:
    """What a record is: which aircraft, where it flew, how it was sampled and made."""

    aircraft: str = ""
    condition: dict[str, Any] = field(default_factory=dict)
    sample_rate: float = 0.0
    provenance: str = ""
    scenario: dict[str, Any] = field(default_factory=dict)
    reference: Reference | None = None
    units: dict[str, str] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> str:
        """Metadata as a JSON string (the form stored in Parquet and CSV files)."""
        d = asdict(self)
        d["format_version"] = FORMAT_VERSION
        return json.dumps(d, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> RecordMeta:
        """Inverse of :meth:`to_json`."""
        d = json.loads(text)
        d.pop("format_version", None)
        ref = d.pop("reference", None)
        return cls(reference=Reference(**ref) if ref else None, **d)


@dataclass
class FlightRecord:
    """Time histories of named channels in SI units, sampled at ``time`` (s)."""

    time: np.ndarray
    channels: dict[str, np.ndarray]
    meta: RecordMeta = field(default_factory=RecordMeta)

    def __post_init__(self) -> None:
        self.time = np.asarray(self.time, dtype=float)
        if self.time.ndim != 1:
            raise ValueError(f"time must be one-dimensional, got shape {self.time.shape}")
        if self.time.size > 1 and np.any(np.diff(self.time) <= 0):
            i = int(np.argmax(np.diff(self.time) <= 0))
            raise ValueError(
                f"time must increase strictly; it does not between samples {i} and {i + 1} "
                f"(t = {self.time[i]!r}, {self.time[i + 1]!r})"
            )
        fixed: dict[str, np.ndarray] = {}
        for name, values in self.channels.items():
            arr = np.asarray(values, dtype=float)
            if arr.shape != self.time.shape:
                raise ValueError(
                    f"channel {name!r} has {arr.shape} samples, time has {self.time.shape}"
                )
            if name not in CHANNELS and name not in self.meta.units:
                raise ValueError(
                    f"channel {name!r} is not canonical (flightid/channels.py) and has no unit "
                    "in meta.units"
                )
            fixed[name] = arr
        self.channels = fixed

    # -- access ---------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise KeyError(
                f"record has no channel {name!r}; it has {', '.join(sorted(self.channels))}"
            ) from None

    def __contains__(self, name: str) -> bool:
        return name in self.channels

    def __len__(self) -> int:
        return int(self.time.size)

    @property
    def dt(self) -> float:
        """Mean sample interval (s)."""
        return float(np.mean(np.diff(self.time))) if len(self) > 1 else 0.0

    def uniform_step(self, purpose: str, min_samples: int = 2, rtol: float = 1e-6) -> float:
        """The sample interval (s) of a uniformly sampled record; raises naming ``purpose``
        when the record is too short or its steps vary by more than ``rtol`` relative."""
        if len(self) < min_samples:
            raise ValueError(f"record has {len(self)} samples; {purpose} needs at least "
                             f"{min_samples}")
        steps = np.diff(self.time)
        dt = float(np.mean(steps))
        if np.max(np.abs(steps - dt)) > rtol * dt + 1e-9:
            i = int(np.argmax(np.abs(steps - dt)))
            raise ValueError(
                f"record is not uniformly sampled (step {steps[i]:.6g} s at sample {i}, mean "
                f"{dt:.6g} s); resample it before {purpose}")
        return dt

    def unit(self, name: str) -> str:
        """SI unit of a channel of this record."""
        if name in self.meta.units:
            return self.meta.units[name]
        return CHANNELS[name].unit

    def with_channels(self, **channels: np.ndarray) -> FlightRecord:
        """A copy with channels added or replaced."""
        return FlightRecord(self.time.copy(), {**self.channels, **channels}, replace(self.meta))

    def slice(self, t_start: float, t_end: float) -> FlightRecord:
        """The part of the record with t_start <= t <= t_end (s)."""
        keep = (self.time >= t_start) & (self.time <= t_end)
        if not keep.any():
            raise ValueError(
                f"no samples between {t_start} s and {t_end} s; record spans "
                f"{self.time[0]} to {self.time[-1]} s"
            )
        return FlightRecord(
            self.time[keep], {k: v[keep] for k, v in self.channels.items()}, replace(self.meta)
        )

    def to_frame(self) -> pd.DataFrame:
        """The channels as a pandas DataFrame with a ``time`` column first."""
        return pd.DataFrame({"time": self.time, **self.channels})

    # -- files ----------------------------------------------------------------
    def write(self, path: str | Path) -> Path:
        """Write to ``.parquet`` or ``.csv`` (chosen by suffix); lossless round trip."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".parquet":
            table = pa.Table.from_pandas(self.to_frame(), preserve_index=False)
            crc = json.dumps({"block": CRC_BLOCK, "columns": {
                name: block_crcs(values) for name, values in
                (("time", self.time), *self.channels.items())}})
            table = table.replace_schema_metadata(
                {**(table.schema.metadata or {}), b"flightid": self.meta.to_json().encode(),
                 _CRC_KEY: crc.encode()}
            )
            with atomic_path(path) as tmp:
                pq.write_table(table, tmp, write_page_checksum=True)
        elif suffix == ".csv":
            with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(_CSV_MARK + self.meta.to_json() + "\n")
                # %.17g round-trips every float64 exactly
                self.to_frame().to_csv(fh, index=False, float_format="%.17g")
        else:
            raise ValueError(f"{path}: unknown record format {suffix!r}; use .parquet or .csv")
        return path


def block_crcs(values: np.ndarray, block: int = CRC_BLOCK) -> list[int]:
    """CRC-32 of the float64 bytes of each block of ``block`` samples.

    Parameters
    ----------
    values : numpy.ndarray
        Samples of one column; written as little-endian float64.
    block : int, optional
        Samples per block. Default ``CRC_BLOCK``.

    Returns
    -------
    list of int
        One CRC-32 per block (one for an empty column).
    """
    data = np.ascontiguousarray(values, dtype="<f8")
    return [zlib.crc32(data[i:i + block].tobytes()) for i in range(0, max(data.size, 1), block)]


def rows_text(bad: np.ndarray) -> str:
    """Text naming the first run of True in ``bad`` and how many more rows follow.

    Parameters
    ----------
    bad : numpy.ndarray
        Boolean mask over the data rows (0-based); at least one True.

    Returns
    -------
    str
        E.g. 'rows 12-15 (and 3 more row(s))'.
    """
    idx = np.flatnonzero(bad)
    first = int(idx[0])
    last = first
    while last + 1 < bad.size and bad[last + 1]:
        last += 1
    where = f"row {first}" if last == first else f"rows {first}-{last}"
    more = idx.size - (last - first + 1)
    return where + (f" (and {more} more row(s))" if more else "")


def check_samples(source: str, time: np.ndarray, channels: dict[str, np.ndarray]) -> None:
    """Refuse a damaged record.

    A time or channel value that is not finite, or time that does not increase, is named by
    the column and its row range.

    Parameters
    ----------
    source : str
        Names the file in the message.
    time : numpy.ndarray
        Sample times, s; shape (n,).
    channels : dict of str to numpy.ndarray
        Channel values by name, each shape (n,).

    Raises
    ------
    ValueError
        Naming the file, column and rows.
    """
    for name, values in (("time", time), *channels.items()):
        bad = ~np.isfinite(values)
        if bad.any():
            raise ValueError(f"{source}: column {name!r} has values that are not finite "
                             f"(NaN or infinite) in {rows_text(bad)}: the file is damaged "
                             "or has gaps; repair or cut it")
    if time.size > 1:
        back = np.diff(time) <= 0
        if back.any():
            i = int(np.argmax(back))
            raise ValueError(f"{source}: column 'time' does not increase in {rows_text(back)} "
                             f"(t = {time[i]:.6g} s then {time[i + 1]:.6g} s): the file is "
                             "damaged or two records were joined")


def _check_crc(path: Path, raw: bytes | None, frame: pd.DataFrame) -> None:
    if not raw:
        return
    try:
        stored = json.loads(raw.decode())
        block, columns = int(stored["block"]), stored["columns"]
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        raise ValueError(f"{path}: its checksums are damaged; the file is corrupt") from None
    for name, crcs in columns.items():
        if name not in frame.columns:
            raise ValueError(f"{path}: column {name!r} is missing; the file is damaged")
        now = block_crcs(frame[name].to_numpy(dtype=float), block)
        for k, (a, b) in enumerate(zip(crcs, now, strict=False)):
            if a != b:
                raise ValueError(
                    f"{path}: column {name!r} rows {k * block}-"
                    f"{min((k + 1) * block, len(frame)) - 1} do not match their checksum: "
                    "the file is damaged")
        if len(crcs) != len(now):
            raise ValueError(f"{path}: column {name!r} has {len(frame)} rows, not the number "
                             "written; the file is damaged")


def read_parquet(path: str | Path) -> FlightRecord:
    """Read a record written as .parquet.

    Metadata comes from the schema's ``flightid`` key; a Parquet file from elsewhere gets only
    its path as provenance.

    Parameters
    ----------
    path : str or pathlib.Path
        The .parquet file.

    Returns
    -------
    FlightRecord
        The record.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    IsADirectoryError
        When the path is a folder.
    ValueError
        Naming the file when it is not Parquet, is truncated or damaged (and, where the damage
        decodes, the column and rows: the block checksums written by
        :meth:`FlightRecord.write`).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder, not a record file")
    try:
        table = pq.read_table(path, page_checksum_verification=True)
        frame = table.to_pandas()
    except (pa.ArrowException, OSError, ValueError, TypeError) as exc:
        reason = " ".join(str(exc).split())[:200]
        where = _damaged_column(path)
        raise ValueError(f"{path}: not a readable Parquet record (damaged, truncated or "
                         f"another format{where}: {reason})") from None
    metadata = table.schema.metadata or {}
    raw = metadata.get(b"flightid")
    meta = _meta(path, raw.decode(errors="replace")) if raw else \
        RecordMeta(provenance=str(path))
    _check_crc(path, metadata.get(_CRC_KEY), frame)
    return _from_frame(path, frame, meta)


def _damaged_column(path: Path) -> str:
    """', column 'q' rows 0-999' when the file's footer still reads and one column chunk
    does not (its page checksum fails or it does not decode); '' otherwise."""
    try:
        pf = pq.ParquetFile(path, page_checksum_verification=True)
        names = pf.schema_arrow.names
    except (pa.ArrowException, OSError, ValueError, TypeError):
        return ""
    start = 0
    for g in range(pf.num_row_groups):
        rows = pf.metadata.row_group(g).num_rows
        for name in names:
            try:
                pf.read_row_group(g, columns=[name])
            except (pa.ArrowException, OSError, ValueError, TypeError):
                return f", column {name!r} rows {start}-{start + rows - 1}"
        start += rows
    return ""


def _meta(path: Path, text: str) -> RecordMeta:
    try:
        return RecordMeta.from_json(text)
    except (ValueError, TypeError, AttributeError) as exc:
        raise ValueError(f"{path}: its flightid metadata is damaged ({exc})") from None


def read_csv(path: str | Path) -> FlightRecord:
    """Read a record written as .csv.

    Metadata is read from the first, marked line; a CSV file from elsewhere gets only its path
    as provenance.

    Parameters
    ----------
    path : str or pathlib.Path
        The .csv file.

    Returns
    -------
    FlightRecord
        The record.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    IsADirectoryError
        When the path is a folder.
    ValueError
        Naming the file when it is not UTF-8 text or not a readable CSV record.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder, not a record file")
    try:
        with open(path, encoding="utf-8") as fh:
            first = fh.readline()
        if first.startswith(_CSV_MARK):
            meta = _meta(path, first[len(_CSV_MARK):])
            frame = pd.read_csv(path, skiprows=1)
        else:
            meta = RecordMeta(provenance=str(path))
            frame = pd.read_csv(path)
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a UTF-8 text file (byte {exc.start}): not a CSV "
                         "record") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        reason = " ".join(str(exc).split())[:200]
        raise ValueError(f"{path}: not a readable CSV record ({reason})") from None
    return _from_frame(path, frame, meta)


def _from_frame(path: Path, frame: pd.DataFrame, meta: RecordMeta) -> FlightRecord:
    if "time" not in frame.columns:
        raise ValueError(f"{path}: no 'time' column (columns: "
                         f"{', '.join(map(str, frame.columns[:12])) or 'none'})")
    if len(frame) == 0:
        raise ValueError(f"{path}: the record has no rows")
    columns: dict[str, np.ndarray] = {}
    for name in frame.columns:
        numbers = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        text = frame[name].to_numpy()
        bad = np.isnan(numbers) & ~pd.isna(text)  # text that does not read as a number
        if bad.any():
            raise ValueError(f"{path}: column {name!r} has values that are not numbers in "
                             f"{rows_text(bad)} (e.g. {str(text[np.argmax(bad)])[:20]!r})")
        columns[str(name)] = numbers
    if len(columns) != len(frame.columns):
        raise ValueError(f"{path}: a column name appears twice")
    time = columns.pop("time")
    check_samples(str(path), time, columns)
    try:
        return FlightRecord(time, columns, meta)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
