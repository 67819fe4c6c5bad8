"""Record a MAVLink stream: every intact packet from a link (serial device, pty, loopback
UDP) into a standard .tlog (``frames.FrameScanner``) and a ``<tlog>.json`` report
(corrupt frames, junk bytes, sequence losses per source).
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from flightid.files import atomic_path, write_text
from flightid.sim.bridge.decoding import message_time
from flightid.sim.bridge.frames import Frame, FrameScanner, TlogWriter
from flightid.sim.bridge.ground.sources import Source, loss_dict, sequence_losses
from flightid.sim.bridge.link import Link


@dataclass
class RecordingReport:
    """What the ground side got: bytes, frames, rejects and per-source losses."""

    tlog: str
    duration: float = 0.0
    scan: dict = field(default_factory=dict)
    sources: dict[str, dict] = field(default_factory=dict)
    ended_by: str = ""

    def as_dict(self) -> dict:
        """Plain data."""
        return dict(vars(self))

    def summary(self) -> str:
        """Readable summary."""
        s = self.scan
        lines = [
            f"{self.tlog}: {s.get('frames', 0)} packets in {self.duration:.1f} s "
            f"({self.ended_by}); {s.get('bytes', 0)} bytes, {s.get('rejected', 0)} corrupt "
            f"frame attempts, {s.get('junk_bytes', 0)} junk bytes"
        ]
        for name, d in self.sources.items():
            lines.append(f"  source {name}: {d['received']} received, {d['lost']} lost "
                         f"({100 * d['loss_rate']:.2f} %)")
        return "\n".join(lines)


def record_stream(
    link: Link, tlog_path: str | Path, *, duration: float | None = None,
    idle_timeout: float = 5.0, first_timeout: float = 30.0, on_frame=None,
    stop: threading.Event | None = None,
) -> RecordingReport:
    """Record intact packets from ``link`` into a .tlog; writes ``<tlog>.json`` too.

    Recording ends when ``duration`` s have passed, the stream ends, nothing arrives for
    ``idle_timeout`` s (``first_timeout`` s before the first byte), or ``stop`` is set and
    nothing is pending. The tlog is written to a temporary file beside ``tlog_path`` and moved
    there when the recording ends (also when it is interrupted: the packets recorded so far
    are kept); an error leaves no partial tlog and an existing file untouched.

    Parameters
    ----------
    link : Link
        The link to read.
    tlog_path : str or pathlib.Path
        The .tlog file to write.
    duration : float, optional
        Longest recording, s; None = no limit.
    idle_timeout : float, optional
        Silence that ends the recording, s. Default 5.
    first_timeout : float, optional
        Wait for the first byte, s. Default 30.
    on_frame : callable, optional
        Called with each intact frame as it is recorded.
    stop : threading.Event, optional
        Ends the recording once nothing is pending.

    Returns
    -------
    RecordingReport
        What was recorded and how the recording ended.

    Raises
    ------
    TimeoutError
        When not a single intact packet arrived (nothing is written).
    """
    tlog_path = Path(tlog_path)
    with atomic_path(tlog_path) as tmp:
        report = _record_into(link, tlog_path, tmp, duration, idle_timeout, first_timeout,
                              on_frame, stop)
        if isinstance(report, RecordingReport) and not report.scan.get("frames"):
            name = getattr(link, "name", "the link")
            junk = report.scan.get("bytes", 0)
            raise TimeoutError(
                f"no MAVLink packet arrived on {name} ({report.ended_by}"
                + (f"; {junk} bytes, none of them an intact packet" if junk else "")
                + f"); nothing written to {tlog_path}")
    if isinstance(report, KeyboardInterrupt):
        raise report
    write_text(str(tlog_path) + ".json", json.dumps(report.as_dict(), indent=2))
    return report


def _record_into(link: Link, tlog_path: Path, tmp: Path, duration: float | None,
                 idle_timeout: float, first_timeout: float, on_frame,
                 stop: threading.Event | None) -> RecordingReport | KeyboardInterrupt:
    """The recording loop of :func:`record_stream`, writing into ``tmp``; an interrupt is
    returned (not raised) so that the packets recorded so far are kept."""
    scanner = FrameScanner()
    writer = TlogWriter(tmp)
    packets: list[tuple[Source, int, float | None]] = []
    start = time.monotonic()
    last_data = None
    ended = "duration"

    def keep(frames: list[Frame]) -> None:
        now = time.time()
        for fr in frames:
            writer.write(now, fr.raw)
            packets.append((fr.source, fr.msg.get_seq(), message_time(fr.msg)))
            if on_frame is not None:
                on_frame(fr)

    try:
        while True:
            now = time.monotonic()
            if duration is not None and now - start >= duration:
                ended = "duration"
                break
            wait = 0.1 if duration is None else max(0.0, min(0.1, start + duration - now))
            data = link.read(wait)
            if data is None:
                ended = "end of stream"
                break
            if not data and stop is not None and stop.is_set():
                ended = "stopped by the sender"
                break
            if data:
                last_data = time.monotonic()
                keep(scanner.feed(data))
                if link.datagrams:
                    keep(scanner.flush())
            elif last_data is None and time.monotonic() - start > first_timeout:
                ended = f"no data within {first_timeout} s"
                break
            elif last_data is not None and time.monotonic() - last_data > idle_timeout:
                ended = f"idle for {idle_timeout} s"
                break
        keep(scanner.flush())
    except KeyboardInterrupt as exc:
        return exc
    finally:
        writer.close()
    return RecordingReport(
        str(tlog_path), time.monotonic() - start, scanner.stats.as_dict(),
        loss_dict(sequence_losses(packets)), ended,
    )
