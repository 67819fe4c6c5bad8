"""Atomic file writes: every file flightid writes goes through :func:`atomic_path`.

The content is written to a temporary file in the target's own folder and moved over the
target with :func:`os.replace` only when the writing finished without an exception. A
failure (an exception, a full disk, a crash) therefore never leaves a half-written file and
never damages a file that was already there. A folder that cannot be written raises an
``OSError`` of the usual type (``PermissionError``, ``FileNotFoundError``,
``NotADirectoryError``, ...) whose message reads ``cannot write <path>: <reason>``.

:func:`content_kind` tells what an existing file holds from its first bytes, so that a
command never writes a file of another kind over it unasked (``flightid.cli.checks``).
"""

from __future__ import annotations

import errno
import math
import numbers
import os
import re
import secrets
import stat
import tomllib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

_REASONS = {
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EROFS: "read-only file system",
    errno.ENOENT: "no such folder",
    errno.ENOTDIR: "a part of the path is not a folder",
    errno.EISDIR: "it is a folder",
    errno.ENOSPC: "no space left on the device",
}


def _cannot_write(path: Path, exc: OSError) -> OSError:
    """The same OSError type, with a message naming the path and the reason."""
    reason = _REASONS.get(exc.errno or 0) or (exc.strerror or str(exc)).lower()
    new = type(exc)(f"cannot write {path}: {reason}")
    new.errno = exc.errno  # (no filename: it would turn the message into "[Errno n] ...")
    return new


def _create_temporary(path: Path) -> Path:
    """A new, empty file beside ``path`` (same suffix, so writers that choose the format
    by suffix still do); created with the mode a plain ``open(path, "w")`` would give."""
    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    for _ in range(100):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp{path.suffix}")
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(path))


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; write the file there.

    On a normal exit the temporary file replaces ``path`` (keeping the mode of a file already
    there); on an exception it is removed and ``path`` is left as it was. A symbolic link is
    written through, not replaced.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.

    Yields
    ------
    pathlib.Path
        The temporary file to write to.

    Raises
    ------
    OSError
        ``cannot write <path>: <reason>`` when the file cannot be created or replaced.
    """
    path = Path(path)
    if path.is_symlink():  # write through the link, do not replace the link by a file
        path = Path(os.path.realpath(path))
    try:
        tmp = _create_temporary(path)
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    try:
        yield tmp
        try:
            os.chmod(tmp, stat.S_IMODE(path.stat().st_mode))
        except FileNotFoundError:
            pass
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise _cannot_write(path, exc) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write(path: str | Path, write: Callable[[Path], Any]) -> Path:
    """Call ``write(temporary_path)`` and move the result onto ``path`` atomically.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.
    write : callable
        Writes the file at the temporary path it is given.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path) as tmp:
        write(tmp)
    return Path(path)


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """``Path.write_text``, atomically.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to write.
    text : str
        Its content.
    encoding : str, optional
        Text encoding. Default "utf-8".

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding=encoding))


def check_writable(path: str | Path) -> None:
    """Raise the OSError :func:`atomic_path` would raise for ``path``, without writing it.

    A temporary file is created beside it and removed. Lets a command refuse an unwritable
    output before its work starts.

    Parameters
    ----------
    path : str or pathlib.Path
        The output file to check.

    Raises
    ------
    OSError
        ``cannot write <path>: <reason>``.
    """
    path = Path(path)
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    try:
        tmp = _create_temporary(path)
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    tmp.unlink(missing_ok=True)
    if path.exists() and not os.access(path, os.W_OK):
        raise _cannot_write(path, PermissionError(errno.EACCES, "permission denied"))


# -- what a file holds, judged by its content ---------------------------------------------

#: the kind of file each output suffix writes
SUFFIX_KINDS = {".parquet": "parquet", ".csv": "csv", ".html": "html", ".htm": "html",
                ".tlog": "tlog", ".json": "json", ".png": "png", ".pdf": "pdf", ".svg": "svg",
                ".xml": "xml", ".mat": "mat"}
_MAGIC = ((b"PAR1", "parquet"), (b"\x89PNG\r\n\x1a\n", "png"), (b"%PDF", "pdf"),
          (b"MATLAB", "mat"))
_MAVLINK_V1, _MAVLINK_V2 = 0xFE, 0xFD


def suffix_kind(path: str | os.PathLike[str]) -> str | None:
    """The kind of file a path's suffix stands for (``SUFFIX_KINDS``), or None.

    Parameters
    ----------
    path : str or os.PathLike
        The file's path; the suffix is compared in lower case.

    Returns
    -------
    str or None
        The kind, or None for an unknown suffix.
    """
    return SUFFIX_KINDS.get(Path(path).suffix.lower())


def _tlog_frame_length(data: bytes, at: int) -> int | None:
    """Length of the tlog entry (8-byte time stamp + MAVLink frame) at ``at``, or None."""
    if len(data) < at + 10:
        return None
    magic = data[at + 8]
    if magic == _MAVLINK_V2:
        signed = 13 if len(data) > at + 10 and data[at + 10] & 0x01 else 0
        return 8 + 12 + data[at + 9] + signed
    if magic == _MAVLINK_V1:
        return 8 + 8 + data[at + 9]
    return None


def content_kind(path: str | os.PathLike[str]) -> str | None:
    """What a file holds, judged by its first bytes (at most 4096).

    Parameters
    ----------
    path : str or os.PathLike
        The file to inspect.

    Returns
    -------
    str or None
        ``parquet``, ``png``, ``pdf``, ``mat`` (MATLAB), ``tlog`` (8-byte time stamps, each
        followed by a MAVLink frame), ``html``, ``svg``, ``xml``, ``json``, ``csv`` (a flightid
        CSV record or a text table with a comma in its first line), ``empty``; None when it
        cannot be told (or the path is not a readable file).
    """
    try:
        with open(path, "rb") as fh:
            data = fh.read(4096)
    except OSError:
        return None
    if not data:
        return "empty"
    for magic, kind in _MAGIC:
        if data.startswith(magic):
            return kind
    first = _tlog_frame_length(data, 0)
    if first is not None and (len(data) < first + 9
                              or _tlog_frame_length(data, first) is not None):
        return "tlog"
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:  # binary, or a character cut at the 4096th byte
        if exc.start < len(data) - 4:
            return None
        text = data[:exc.start].decode("utf-8")
    text = text.lstrip("\ufeff \t\r\n")
    low = text[:1024].lower()
    if low.startswith(("<!doctype html", "<html")):
        return "html"
    if "<svg" in low and low.startswith(("<svg", "<?xml")):
        return "svg"
    if low.startswith("<?xml") or low.startswith("<"):
        return "xml"
    if low.startswith("{") or re.match(r"\[\s*[\[{\"\d\-\]tfn]", low):
        return "json"  # (a TOML table "[name]" is not JSON)
    line = text.split("\n", 1)[0]
    if line.startswith("# flightid-record") or "," in line:
        return "csv"
    return None


def read_toml(path: str | Path, what: str, kind: str = "TOML file") -> dict[str, Any]:
    """The tables of the TOML file ``path``.

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.
    what : str
        What the file is, for the missing-file message ("no such ``what``").
    kind : str, optional
        What the file should be, for the unreadable-file message. Default "TOML file".

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    ValueError
        Naming the file when it is not readable TOML.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such {what}")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable {kind} ({exc})") from None


def json_safe(value: Any) -> Any:
    """``value`` ready for strict JSON (RFC 8259 has no NaN or infinity).

    Parameters
    ----------
    value : Any
        A number, or dicts, lists and tuples of them, numpy scalars included.

    Returns
    -------
    Any
        The same structure (tuples as lists) with every non-finite number as None, numpy
        floats as float and numpy integers as int; everything else unchanged.
    """
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value) if math.isfinite(value) else None
    return value
