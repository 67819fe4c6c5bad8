"""MAVLink framing on the ground side: a resynchronising scanner, and .tlog files.

pymavlink's stream parser drops a whole frame's worth of bytes after a bad frame, so one
corrupted length byte also swallows the intact packets behind it. The scanner here tries
a frame at every start marker and, when the CRC (with CRC_EXTRA), the length or the
flags are wrong, moves on by one byte: every intact packet in the stream is found
(a random frame passes the 16-bit CRC with probability 2^-16). Decoding and the CRC
check are pymavlink's (``MAVLink.decode``).

A .tlog is what mavutil writes: for each packet an 8-byte big-endian unix time in
microseconds, then the raw packet.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

_STX = re.compile(b"[\xfd\xfe]")
_V2, _V1 = 0xFD, 0xFE
_SIGNED = 0x01


@dataclass
class Frame:
    """One intact packet: its bytes and the decoded pymavlink message."""

    raw: bytes
    msg: object

    @property
    def source(self) -> tuple[int, int]:
        """(sysid, compid) of the sender."""
        return self.msg.get_srcSystem(), self.msg.get_srcComponent()


@dataclass
class ScanStats:
    """What the scanner saw: good frames, rejected frame attempts, bytes outside frames."""

    bytes: int = 0
    frames: int = 0
    rejected: int = 0  # candidate frames failing CRC / length / flags
    unknown_id: int = 0  # candidate frames naming a message the dialect lacks
    junk_bytes: int = 0  # bytes not part of any intact frame
    reasons: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict:
        """Plain data."""
        return dict(vars(self))


def _frame_length(buf: bytes | bytearray, i: int) -> int | None:
    """Total length of the frame starting at i, None if its header is implausible."""
    if buf[i] == _V2:
        flags = buf[i + 2]
        if flags & ~_SIGNED:
            return None
        return 12 + buf[i + 1] + (13 if flags & _SIGNED else 0)
    return 8 + buf[i + 1]


class FrameScanner:
    """Feed bytes, get intact frames; counts what it had to throw away."""

    def __init__(self) -> None:
        self.mav = mavlink2.MAVLink(None)
        self.buf = bytearray()
        self.stats = ScanStats()

    def _reject(self, reason: str) -> None:
        self.stats.rejected += 1
        self.stats.reasons[reason] = self.stats.reasons.get(reason, 0) + 1

    def _scan(self, final: bool) -> list[Frame]:
        buf, out, i = self.buf, [], 0
        n = len(buf)
        good_end = 0  # end of the last byte accounted for (frame or junk)
        while True:
            m = _STX.search(buf, i)
            if m is None:
                i = n
                break
            j = m.start()
            header = 10 if buf[j] == _V2 else 6
            if n - j < header:
                if final:
                    i = n
                else:
                    i = j
                break
            length = _frame_length(buf, j)
            if length is None:
                self._reject("bad incompat flags")
                i = j + 1
                continue
            if n - j < length:
                if final:
                    self._reject("truncated frame")
                    i = j + 1
                    continue
                i = j
                break
            raw = bytes(buf[j:j + length])
            try:
                msg = self.mav.decode(bytearray(raw))
            except mavlink2.MAVError as exc:
                self._reject(exc.message.split(" in ")[0].split(".")[0][:40])
                i = j + 1
                continue
            if isinstance(msg, mavlink2.MAVLink_unknown):
                self.stats.unknown_id += 1
                i = j + 1
                continue
            self.stats.junk_bytes += j - good_end
            out.append(Frame(raw, msg))
            self.stats.frames += 1
            i = good_end = j + length
        self.stats.junk_bytes += i - good_end
        del buf[:i]
        return out

    def feed(self, data: bytes) -> list[Frame]:
        """Add received bytes; return the intact frames now complete."""
        self.stats.bytes += len(data)
        self.buf.extend(data)
        return self._scan(final=False)

    def flush(self) -> list[Frame]:
        """End of stream (or of a datagram): resolve what is left in the buffer."""
        out = self._scan(final=True)
        self.stats.junk_bytes += len(self.buf)
        self.buf.clear()
        return out


# -- tlog ---------------------------------------------------------------------------------


class TlogWriter:
    """Appends packets to a .tlog (8-byte big-endian unix usec + packet)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.fh = open(self.path, "wb")
        self.count = 0

    def write(self, unix_time: float, raw: bytes) -> None:
        """One packet received at unix time (s)."""
        self.fh.write(struct.pack(">Q", int(unix_time * 1e6)) + raw)
        self.count += 1

    def close(self) -> None:
        """Flush and close."""
        self.fh.close()


@dataclass
class TlogEntry:
    """One packet read from a tlog: ground receive time (unix s) and frame."""

    t_recv: float
    frame: Frame


@dataclass
class TlogRead:
    """A tlog's packets and what could not be read."""

    entries: list[TlogEntry]
    size: int
    skipped_bytes: int = 0  # unreadable bytes between good records
    truncated_bytes: int = 0  # bytes after the last good record (a cut file)
    notes: list[str] = field(default_factory=list)


def _plausible(data: bytes, pos: int, mav, last_usec: int | None) -> tuple[int, Frame] | None:
    """The record at pos if it is a timestamp followed by one intact frame."""
    if len(data) - pos < 8 + 8:
        return None
    if data[pos + 8] not in (_V2, _V1):
        return None
    usec = struct.unpack_from(">Q", data, pos)[0]
    if last_usec is not None and abs(usec - last_usec) > 86_400e6:
        return None  # a day's jump: not a timestamp of this log
    length = _frame_length(data, pos + 8)
    if length is None or pos + 8 + length > len(data):
        return None
    raw = data[pos + 8:pos + 8 + length]
    try:
        msg = mav.decode(bytearray(raw))
    except mavlink2.MAVError:
        return None
    if isinstance(msg, mavlink2.MAVLink_unknown):
        return None
    return usec, Frame(bytes(raw), msg)


def read_tlog(path: str | Path) -> TlogRead:
    """All intact packets of a .tlog; a cut or damaged file is read up to what is good.

    Unreadable bytes between good packets are skipped and noted.

    Parameters
    ----------
    path : str or pathlib.Path
        The .tlog file.

    Returns
    -------
    TlogRead
        The packets with their time stamps (s), the file size, and the bytes skipped or cut
        with notes naming their offsets.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    data = path.read_bytes()
    mav = mavlink2.MAVLink(None)
    entries: list[TlogEntry] = []
    pos, last, skipped = 0, None, 0
    result = TlogRead(entries, len(data))
    while pos < len(data):
        rec = _plausible(data, pos, mav, last)
        if rec is not None:
            usec, frame = rec
            entries.append(TlogEntry(usec * 1e-6, frame))
            pos += 8 + len(frame.raw)
            last = usec
            continue
        # find the next position where a good record starts
        nxt = pos + 1
        while nxt < len(data):
            m = _STX.search(data, nxt + 8)
            if m is None:
                nxt = len(data)
                break
            cand = m.start() - 8
            if _plausible(data, cand, mav, last) is not None:
                nxt = cand
                break
            nxt = cand + 1
        if nxt >= len(data):
            result.truncated_bytes = len(data) - pos
            result.notes.append(
                f"{path}: {len(data) - pos} bytes after the last good packet (offset {pos}, "
                f"packet {len(entries)}) could not be read: file cut or damaged at its end"
            )
            break
        result.notes.append(f"{path}: skipped {nxt - pos} unreadable bytes at offset {pos}")
        skipped += nxt - pos
        pos = nxt
    result.skipped_bytes = skipped
    return result
