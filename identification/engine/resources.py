"""The resource guard: the memory a command will need, estimated from the record's sample
count before the record is read, against the memory the system reports available.

The cost per sample of each kind of work is the peak resident memory measured on
12,500- and 50,000-sample Navion records (``/usr/bin/time -f %M``; docs/errors.md,
"Resource guard"), plus a fixed 300 MB for the interpreter, numpy, scipy and JSBSim.
A command refuses when the estimate exceeds ``MARGIN`` of the available memory (Linux:
``MemAvailable`` of /proc/meminfo; elsewhere the physical pages os.sysconf reports),
naming the sample count and the estimate; ``force`` overrides.
"""

from __future__ import annotations

import os
from pathlib import Path

import pyarrow.parquet as pq

BASE_BYTES = 300e6
# peak bytes per record sample (a record of about 30 channels), by method id or command:
# the slope of the peak resident memory between 12,500 and 50,000 samples (ee, oe, fr,
# frequency-response) or the peak at 50,000 samples less the 260 MB of the interpreter
# and libraries (the others); oe6dof and compatibility were stopped after 11 and 12
# minutes at 1.8 GB and 2.7 GB, so theirs are lower bounds; bridge serve only reads and
# streams the record (the reader's 1.3 kB)
BYTES_PER_SAMPLE: dict[str, float] = {
    "ee": 2300.0, "swr": 2800.0, "fdee": 2400.0, "fdoe": 2200.0, "fr": 2800.0,
    "oe": 9900.0, "fem": 7700.0, "oe6dof": 31000.0, "compatibility": 50000.0,
    "frequency-response": 3400.0, "gap": 9900.0, "bridge serve": 1400.0,
}
DEFAULT_BYTES_PER_SAMPLE = 9900.0  # a method not measured: as output error
MARGIN = 0.8  # of the available memory
_CSV_PROBE_BYTES = 1 << 16


def estimated_bytes(samples: int, work: str) -> float:
    """Peak memory of ``work`` on ``samples`` samples.

    Parameters
    ----------
    samples : int
        The record's sample count.
    work : str
        A method id or a command.

    Returns
    -------
    float
        The estimate, bytes.
    """
    return BASE_BYTES + samples * BYTES_PER_SAMPLE.get(work, DEFAULT_BYTES_PER_SAMPLE)


def available_bytes() -> float:
    """Memory the system reports available.

    Returns
    -------
    float
        Available memory, bytes.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))


def samples_in_file(path: str | Path) -> int | None:
    """The sample count of a record file without reading its values.

    The Parquet metadata's row count; for CSV the file size over the length of its first data
    lines.

    Parameters
    ----------
    path : str or Path
        The record file.

    Returns
    -------
    int or None
        The (estimated) sample count; None for other formats (SIDPAC .mat files are small) or
        an unreadable file (the reader names the problem).
    """
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
    """Refuse when ``work`` on ``samples`` samples would need more than ``MARGIN`` of the
    available memory, unless ``force``.

    Parameters
    ----------
    samples : int
        The record's sample count.
    work : str
        A method id or a command.
    what : str
        The record, named in the error.
    force : bool, optional
        Go on anyway. Default False.

    Raises
    ------
    ValueError
        When the memory would not suffice and not ``force``.
    """
    need = estimated_bytes(samples, work)
    have = available_bytes()
    if need > MARGIN * have and not force:
        raise ValueError(
            f"{what} has {samples:,} samples: {work} would need about {need / 1e9:.3g} GB "
            f"of memory, more than {MARGIN:.0%} of the {have / 1e9:.3g} GB available; cut "
            "the record (a window) or lower its rate, or add --force")
