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
            table = table.replace_schema_metadata(
                {**(table.schema.metadata or {}), b"flightid": self.meta.to_json().encode()}
            )
            with atomic_path(path) as tmp:
                pq.write_table(table, tmp)
        elif suffix == ".csv":
            with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(_CSV_MARK + self.meta.to_json() + "\n")
                # %.17g round-trips every float64 exactly
                self.to_frame().to_csv(fh, index=False, float_format="%.17g")
        else:
            raise ValueError(f"{path}: unknown record format {suffix!r}; use .parquet or .csv")
        return path


def read_parquet(path: str | Path) -> FlightRecord:
    """Read a record written as .parquet (metadata from the schema's ``flightid`` key; a
    Parquet file from elsewhere gets only its path as provenance)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    table = pq.read_table(path)
    raw = (table.schema.metadata or {}).get(b"flightid")
    meta = RecordMeta.from_json(raw.decode()) if raw else RecordMeta(provenance=str(path))
    return _from_frame(path, table.to_pandas(), meta)


def read_csv(path: str | Path) -> FlightRecord:
    """Read a record written as .csv (metadata on the first, marked line; a CSV file from
    elsewhere gets only its path as provenance)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    with open(path, encoding="utf-8") as fh:
        first = fh.readline()
    if first.startswith(_CSV_MARK):
        meta = RecordMeta.from_json(first[len(_CSV_MARK):])
        frame = pd.read_csv(path, skiprows=1)
    else:
        meta = RecordMeta(provenance=str(path))
        frame = pd.read_csv(path)
    return _from_frame(path, frame, meta)


def _from_frame(path: Path, frame: pd.DataFrame, meta: RecordMeta) -> FlightRecord:
    if "time" not in frame.columns:
        raise ValueError(f"{path}: no 'time' column")
    time = frame.pop("time").to_numpy(dtype=float)
    return FlightRecord(time, {c: frame[c].to_numpy(dtype=float) for c in frame.columns}, meta)
