"""Where a study lives: STUDY/study.json (description and versions) and one Parquet file
per finished realization under STUDY/results/ (written atomically: a temporary name, then
``os.replace``). What is stored is never recomputed: ``done(study_dir)`` lists it, and a
rerun with the same description runs only the rest (a larger n extends the study)."""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Iterable, Sequence
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from flightid.scenarios.montecarlo.study import COLUMNS, FLOAT_COLUMNS, Study

DESCRIPTION = "study.json"
RESULTS = "results"
_PREFIX, _SUFFIX = "realization-", ".parquet"
# what the summary and the report read
SUMMARY_COLUMNS = ("index", "name", "truth", "estimate", "std", "error", "status", "reason")


# identity keys kept for information only: the card's path or name (the same card given
# by another path, absolute or relative, is the same study when card_sha256 is equal)
INFORMATION_ONLY = ("card",)


class StudyMismatch(ValueError):
    """A stored study was described differently from the run that wants to continue it."""


def versions() -> dict[str, str]:
    """The versions that produced a study (flightid, jsbsim, numpy, python).

    Returns
    -------
    dict[str, str]
        Package -> version ("unknown" if not installed).
    """
    out = {}
    for name in ("flightid", "jsbsim", "numpy"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "unknown"
    out["python"] = platform.python_version()
    return out


def result_path(study_dir: str | Path, index: int) -> Path:
    """Where a study keeps one realization's result.

    Parameters
    ----------
    study_dir : str or Path
        The study's folder.
    index : int
        The realization's index.

    Returns
    -------
    Path
        The result's file below the study's results folder.
    """
    return Path(study_dir) / RESULTS / f"{_PREFIX}{int(index):06d}{_SUFFIX}"


def open_study(study_dir: str | Path, description: Study) -> dict[str, Any]:
    """Create STUDY/ for ``description``, or check that the stored study has the same
    identity (the card's content hash, method, model, options, base seed, dispersions;
    not the card's path, kept for information; n may differ: a larger n extends it).
    Raises StudyMismatch naming each difference. Returns the stored description
    document.

    Parameters
    ----------
    study_dir : str or Path
        The study folder STUDY.
    description : Study
        The study.

    Returns
    -------
    dict[str, Any]
        The stored description document.
    """
    root = Path(study_dir)
    path = root / DESCRIPTION
    identity = description.identity()
    if path.exists():
        stored = _read_json(path)
        old = stored["identity"]
        keys = [k for k in sorted(set(old) | set(identity))
                if k not in INFORMATION_ONLY and old.get(k) != identity.get(k)]
        diffs = [f"{k}: not stored, asked {identity[k]!r} (a study of an earlier flightid, "
                 "whose rows were identified without it)" if k not in old else
                 f"{k}: stored {old.get(k)!r}, asked {identity.get(k)!r}" for k in keys]
        if diffs:
            raise StudyMismatch(f"{root} holds another study ({'; '.join(diffs)}); "
                                "use another folder or the stored description")
        if description.n > int(stored["description"]["n"]):
            stored["description"]["n"] = int(description.n)
            _write_json(path, stored)
        return stored
    (root / RESULTS).mkdir(parents=True, exist_ok=True)
    stored = {"description": description.as_dict(), "identity": identity,
              "versions": versions(), "created": datetime.now(UTC).isoformat()}
    _write_json(path, stored)
    return stored


def read_description(study_dir: str | Path) -> dict[str, Any]:
    """The stored study.json of ``study_dir``.

    Parameters
    ----------
    study_dir : str or Path
        The study folder.

    Returns
    -------
    dict[str, Any]
        The description document.
    """
    path = Path(study_dir) / DESCRIPTION
    if not path.exists():
        raise FileNotFoundError(f"{study_dir}: not a Monte Carlo study (no {DESCRIPTION})")
    return _read_json(path)


def _read_json(path: Path) -> dict[str, Any]:
    """A study.json with its description and identity; a damaged one raises ValueError
    naming it."""
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
        if not (isinstance(stored, dict) and isinstance(stored.get("identity"), dict)
                and isinstance(stored.get("description"), dict)):
            raise ValueError("no 'identity' and 'description' objects")
        int(stored["description"]["n"])
    except (ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: a damaged study description ({type(exc).__name__}: "
                         f"{exc}); restore it, or start the study in another folder") from None
    return stored


def _write_json(path: Path, data: dict[str, Any]) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=2) + "\n")
    os.replace(tmp, path)


def frame(rows: Iterable[dict[str, Any]]) -> pd.DataFrame:
    """Result rows as a DataFrame with the study's columns and dtypes; any other key of
    the rows (the drawn dispersions, ``disperse:<parameter>``) follows as a float column.

    Parameters
    ----------
    rows : Iterable[dict[str, Any]]
        Result rows.

    Returns
    -------
    pandas.DataFrame
        One row per input row.
    """
    rows = list(rows)
    extra = sorted({k for r in rows for k in r} - set(COLUMNS))
    df = pd.DataFrame(rows, columns=[*COLUMNS, *extra])
    df = df.astype({"index": "int64", "seed": "int64", "name": str, "status": str,
                    "reason": str, **{c: "float64" for c in (*FLOAT_COLUMNS, *extra)}})
    return df


def write_realization(study_dir: str | Path, index: int, rows: list[dict[str, Any]]) -> Path:
    """Store one realization's rows (atomically: a reader sees all of them or none).

    Parameters
    ----------
    study_dir : str or Path
        The study folder.
    index : int
        Realization index.
    rows : list[dict[str, Any]]
        Its rows.

    Returns
    -------
    Path
        The written Parquet file.
    """
    path = result_path(study_dir, index)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    frame(rows).to_parquet(tmp, index=False)
    os.replace(tmp, path)
    return path


def done(study_dir: str | Path) -> set[int]:
    """The indices of the realizations already stored in ``study_dir``.

    Parameters
    ----------
    study_dir : str or Path
        The study folder.

    Returns
    -------
    set[int]
        Stored realization indices.
    """
    folder = Path(study_dir) / RESULTS
    if not folder.is_dir():
        return set()
    out = set()
    for p in folder.glob(f"{_PREFIX}*{_SUFFIX}"):
        index = p.name[len(_PREFIX):-len(_SUFFIX)]
        if not index.isdigit():
            raise ValueError(f"{p}: not a realization result of this study (expected "
                             f"{_PREFIX}NNNNNN{_SUFFIX}); move it out of {folder}")
        out.add(int(index))
    return out


def load(study_dir: str | Path, columns: Sequence[str] | None = None) -> pd.DataFrame:
    """Every stored row of the study, sorted by realization index and derivative name.

    Read as Arrow tables and concatenated once: 10,000 realizations load in 8 s (53 s with
    one DataFrame per file; docs/montecarlo.md).

    Parameters
    ----------
    study_dir : str or Path
        The study folder.
    columns : Sequence[str] or None, optional
        Columns to read, their strings as categories (the summary and the report read
        ``SUMMARY_COLUMNS``); None reads every column any realization has (the
        dispersions drawn).

    Returns
    -------
    pandas.DataFrame
        The rows.
    """
    files = sorted((Path(study_dir) / RESULTS).glob(f"{_PREFIX}*{_SUFFIX}"))
    if not files:
        empty = frame([])
        return empty[list(columns)] if columns is not None else empty
    tables = []
    for f in files:  # ParquetFile.read: the cheapest whole-file read of pyarrow
        try:
            with pq.ParquetFile(f) as handle:
                tables.append(handle.read(
                    columns=list(columns) if columns is not None else None,
                    use_threads=False))
        except (OSError, pa.ArrowException, ValueError) as exc:
            raise ValueError(f"{f}: a damaged realization result ({exc}); remove it and "
                             "rerun the study to compute it again") from None
    # (a failed realization has no dispersion columns: they are null there)
    table = pa.concat_tables(tables, promote_options="default")
    df = table.to_pandas(strings_to_categorical=columns is not None)
    return df.sort_values(["index", "name"], kind="stable").reset_index(drop=True)
