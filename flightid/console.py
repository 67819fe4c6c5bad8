"""Console output of compiled libraries (JSBSim, pymavlink's log indexer), which write to
the process's file descriptors 1 and 2 directly, around Python's ``sys.stdout`` and
``sys.stderr``: captured, so that a command prints only its own lines."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator


@contextlib.contextmanager
def captured_output() -> Iterator[list[str]]:
    """Capture everything written to file descriptors 1 and 2 inside the block.

    Captures both Python's and compiled code's output.

    Yields
    ------
    list of str
        Empty inside the block; after it, the captured non-blank lines, stripped.
    """
    lines: list[str] = []
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as sink:
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield lines
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            sink.seek(0)
            text = sink.read().decode("utf-8", errors="replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())
