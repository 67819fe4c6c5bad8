"""Atomic file writes: every file flightid writes goes through :func:`atomic_path`.

The content is written to a temporary file in the target's own folder and moved over the
target with :func:`os.replace` only when the writing finished without an exception. A
failure (an exception, a full disk, a crash) therefore never leaves a half-written file and
never damages a file that was already there. A folder that cannot be written raises an
``OSError`` of the usual type (``PermissionError``, ``FileNotFoundError``,
``NotADirectoryError``, ...) whose message reads ``cannot write <path>: <reason>``.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
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
    """Yield a temporary path beside ``path``; write the file there. On a normal exit the
    temporary file replaces ``path`` (keeping the mode of a file already there); on an
    exception it is removed and ``path`` is left as it was."""
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
    """Call ``write(temporary_path)`` and move the result onto ``path`` atomically;
    returns ``path``."""
    with atomic_path(path) as tmp:
        write(tmp)
    return Path(path)


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """``Path.write_text``, atomically."""
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding=encoding))


def check_writable(path: str | Path) -> None:
    """Raise the OSError :func:`atomic_path` would raise for ``path`` (``cannot write
    <path>: <reason>``), without writing it: a temporary file is created beside it and
    removed. Lets a command refuse an unwritable output before its work starts."""
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
