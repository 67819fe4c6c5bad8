"""A stopped ``montecarlo --workers 2`` leaves nothing behind (issue 38): the command runs
as a real process, and once its workers fly, it is sent SIGKILL, SIGTERM or SIGINT. Every
process it started (the forkserver, the resource tracker, the two workers), recorded from
/proc before the signal, must be gone within 10 s.

The workers end because each watches the study's process (``executors._exit_with``: a
pidfd, or polling); the forkserver and the resource tracker end when their pipes close.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

GONE_WITHIN_S = 10.0


def _start_time(pid: int) -> str | None:
    """The start time (clock ticks after boot) of a live process, None once it is gone
    or a zombie (a pid reused by another process has another start time)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat[stat.rindex(")") + 2:].split()
    return None if fields[0] == "Z" else fields[19]


def _descendants(root: int) -> dict[int, str]:
    """{pid: start time} of every live descendant of ``root``."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            ppid = int(stat[stat.rindex(")") + 2:].split()[1])
            children.setdefault(ppid, []).append(int(entry))
    out, todo = {}, [root]
    while todo:
        for child in children.get(todo.pop(), []):
            start = _start_time(child)
            if start is not None:
                out[child] = start
                todo.append(child)
    return out


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_no_process_outlives_a_stopped_study(tmp_path, sig):
    cli = subprocess.Popen(
        [sys.executable, "-m", "flightid.cli.app", "montecarlo", "navion-demo", "-n", "40",
         "-o", str(tmp_path / "study"), "--workers", "2", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    try:
        end = time.monotonic() + 120
        started: dict[int, str] = {}
        while time.monotonic() < end and cli.poll() is None:
            started = _descendants(cli.pid)
            if len(started) >= 4:  # forkserver, resource tracker, two workers
                break
            time.sleep(0.2)
        assert len(started) >= 4, (started, cli.poll())
        while time.monotonic() < end and not any((tmp_path / "study").rglob("*.parquet")):
            time.sleep(0.2)  # the workers fly: the first realization is stored
        started.update(_descendants(cli.pid))
        cli.send_signal(sig)
        cli.wait(timeout=30)
        end = time.monotonic() + GONE_WITHIN_S
        alive = started
        while time.monotonic() < end:
            alive = {p: s for p, s in started.items() if _start_time(p) == s}
            if not alive:
                break
            time.sleep(0.1)
        assert not alive, {p: Path(f"/proc/{p}/cmdline").read_bytes()[:80] for p in alive}
    finally:
        if cli.poll() is None:
            cli.kill()
        cli.communicate()
