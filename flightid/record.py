"""The flight record: time (s), named channels in SI units, and metadata.

Everything in flightid passes through this one type; import it from here. The type and
its own formats (Parquet, CSV) are defined in ``flightid.flight_record`` and re-exported
here; this module adds :func:`read`, the one reader of every record format, which hands
SIDPAC .mat files to ``flightid.sidpac`` (a reader that builds records, so it sits between
the type and this module: no import cycle).
"""

from __future__ import annotations

from pathlib import Path

from flightid.flight_record import (
    FORMAT_VERSION,
    FlightRecord,
    RecordMeta,
    Reference,
    read_csv,
    read_parquet,
)
from flightid.sidpac import read_mat

__all__ = ["FORMAT_VERSION", "FlightRecord", "RecordMeta", "Reference", "read", "read_csv",
           "read_mat", "read_parquet"]

_READERS = {".parquet": read_parquet, ".csv": read_csv, ".mat": read_mat}


def read(path: str | Path) -> FlightRecord:
    """Read a flight record from .parquet, .csv (as written by flightid) or SIDPAC .mat.

    Parameters
    ----------
    path : str or Path
        The file; its suffix names the format.

    Returns
    -------
    FlightRecord
        The record, in SI units with angles in rad.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in _READERS:
        raise ValueError(f"{path}: unknown record format {suffix!r}; use .parquet, .csv or .mat")
    return _READERS[suffix](path)
