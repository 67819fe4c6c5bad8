"""The resource guard: the memory a command will need, estimated from the record's sample
count before the record is read, against the memory the system reports available.

The cost per sample of each kind of work is the peak resident memory measured on a
50,000-sample Navion record (docs/errors.md, "Resource guard"), rounded up, plus a
fixed 400 MB for the interpreter, numpy, scipy and JSBSim. A command refuses when the
estimate exceeds ``MARGIN`` of the available memory (Linux: ``MemAvailable`` of
/proc/meminfo; elsewhere the physical pages os.sysconf reports), naming the sample count
and the estimate; ``force`` overrides.
"""

from __future__ import annotations

import os
from pathlib import Path

import pyarrow.parquet as pq

BASE_BYTES = 400e6
# peak bytes per record sample (all channels), by method id or command
BYTES_PER_SAMPLE: dict[str, float] = {
    "read": 600.0, "ee": 1400.0, "swr": 1400.0, "oe": 2500.0, "fdee": 1400.0,
    "fdoe": 1400.0, "fr": 2500.0, "fem": 2500.0, "oe6dof": 2500.0,
    "compatibility": 2500.0, "frequency-response": 2200.0, "gap": 2500.0,
}
DEFAULT_BYTES_PER_SAMPLE = 2500.0
MARGIN = 0.8  # of the available memory
_CSV_PROBE_BYTES = 1 << 16


def estimated_bytes(samples: int, work: str) -> float:
    """Peak memory (bytes) of ``work`` (a method id or a command) on ``samples`` samples."""
    return BASE_BYTES + samples * BYTES_PER_SAMPLE.get(work, DEFAULT_BYTES_PER_SAMPLE)


def available_bytes() -> float:
    """Memory the system reports available (bytes)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))


def samples_in_file(path: str | Path) -> int | None:
    """The sample count of a record file without reading its values: the Parquet
    metadata's row count; for CSV the file size over the length of its first data lines;
    None for other formats (SIDPAC .mat files are small) or an unreadable file (the
    reader names the problem)."""
    path = Path(path)
    suffix = path.suffix.lower()
    try:
        if suffix == ".parquet":
            return int(pq.ParquetFile(path).metadata.num_rows)
        if suffix == ".csv":
            size = path.stat().st_size
            with open(path, "rb") as f:
                head = f.read(_CSV_PROBE_BYTES)
            rows = [r for r in head.split(b"\n")[:-1] if r and not r.startswith(b"#")]
            if len(rows) < 2:
                return None
            return int(size / (sum(map(len, rows[1:])) / (len(rows) - 1) + 1))
    except Exception:  # a damaged file: the reader names the problem
        return None
    return None


def check_memory(samples: int, work: str, what: str, force: bool = False) -> None:
    """Refuse (ValueError) when ``work`` on ``samples`` samples would need more than
    ``MARGIN`` of the available memory, unless ``force``."""
    need = estimated_bytes(samples, work)
    have = available_bytes()
    if need > MARGIN * have and not force:
        raise ValueError(
            f"{what} has {samples:,} samples: {work} would need about {need / 1e9:.3g} GB "
            f"of memory, more than {MARGIN:.0%} of the {have / 1e9:.3g} GB available; cut "
            "the record (a window) or lower its rate, or add --force")
