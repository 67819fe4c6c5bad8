"""Who may fly the aircraft: the ground station's ids and MAVLink 2 message signing.

A signed MAVLink 2 packet (incompat flag 0x01) carries 13 bytes after its CRC: a link id
(1 byte), a timestamp (6 bytes, little-endian, in 10 us units since 2015-01-01 00:00 UTC)
and the first 6 bytes of SHA-256(secret key + the packet up to and including the
timestamp), with a 32-byte secret key shared by both ends (MAVLink 2 "Message signing";
as ArduPilot and PX4 use it). A receiver accepts a packet only if the signature matches
and its timestamp is newer than the last one accepted on the same (link id, system,
component) stream, so a recorded packet cannot be replayed. A stream not seen before is
accepted only if its timestamp is at most 60 s behind the receiver's own signing clock
(the larger of the wall clock and the newest timestamp ever accepted), as the
specification and pymavlink's ``check_signature`` have it. The last timestamps persist
across runs in a state file beside the key (:func:`state_path`), so the packets of an
earlier run stay refused in the next one.

The signature is checked here before the timestamp is stored (pymavlink's
``check_signature`` stores the timestamp first, so one forged packet with a large
timestamp would lock the real sender out). Outgoing packets are signed by pymavlink
(``MAVLink.signing``), as ``mavutil``'s ``setup_signing`` does.
"""

from __future__ import annotations

import hashlib
import json
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

from flightid.files import write_text

#: unix time of the MAVLink signing epoch (2015-01-01 00:00:00 UTC)
SIGNING_EPOCH_UNIX = 1_420_070_400
KEY_BYTES = 32
SIGNATURE_BYTES = 13  # link id, 6-byte timestamp, 6-byte signature
_SIGNED_FLAG = 0x01
#: a new stream may start at most this far behind the receiver's clock (10 us units: 60 s)
NEW_STREAM_WINDOW = 60 * 100_000
#: the state file is written at most this often while packets are accepted (s)
SAVE_INTERVAL_S = 1.0
#: reasons a packet is refused, in the report ("stale": a new stream more than 60 s old;
#: "not finite": a control message carrying NaN or an infinity)
REASONS = ("other sender", "unsigned", "bad signature", "replayed", "stale", "not finite")


def state_path(key_path: str | Path) -> Path:
    """The file beside a key holding the last accepted timestamp of every stream.

    Parameters
    ----------
    key_path : str or pathlib.Path
        The signing key file.

    Returns
    -------
    pathlib.Path
        ``<key>.timestamps.json``.
    """
    key_path = Path(key_path)
    return key_path.with_name(key_path.name + ".timestamps.json")


def read_state(path: str | Path) -> dict[tuple[int, int, int], int]:
    """Last accepted signing timestamps from a state file; empty if it does not exist.

    Parameters
    ----------
    path : str or pathlib.Path
        The state file.

    Returns
    -------
    dict
        {(link id, system, component): last accepted timestamp (10 us units)}.

    Raises
    ------
    ValueError
        Naming the file when it is damaged.
    """
    path = Path(path)
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return {tuple(int(x) for x in key.split("/")): int(stamp)  # type: ignore[misc]
                for key, stamp in data["streams"].items()}
    except (ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a signing timestamp file ({type(exc).__name__}: "
                         f"{exc}); it must be restored or removed (removing it lets the "
                         "packets of the last 60 s be replayed once)") from None


def write_state(path: str | Path, streams: dict[tuple[int, int, int], int]) -> None:
    """Write the last accepted timestamps (atomically).

    Parameters
    ----------
    path : str or pathlib.Path
        The state file.
    streams : dict
        {(link id, system, component): last accepted timestamp (10 us units)}.
    """
    text = json.dumps({"format": "flightid signing timestamps 1",
                       "streams": {"/".join(map(str, k)): v for k, v in sorted(streams.items())}},
                      indent=1)
    write_text(path, text + "\n")


def read_key(path: str | Path) -> bytes:
    """A 32-byte signing key from a file.

    Parameters
    ----------
    path : str or pathlib.Path
        The key file: 32 raw bytes, or 64 hexadecimal digits (text, white space ignored).

    Returns
    -------
    bytes
        The 32-byte key.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    ValueError
        Naming the file when it holds neither form.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such key file")
    data = path.read_bytes()
    if len(data) == KEY_BYTES:
        return data
    text = re.sub(rb"\s+", b"", data)
    if len(text) == 2 * KEY_BYTES and re.fullmatch(rb"[0-9a-fA-F]+", text):
        return bytes.fromhex(text.decode())
    raise ValueError(f"{path}: a signing key is {KEY_BYTES} raw bytes or {2 * KEY_BYTES} "
                     f"hexadecimal digits; the file holds {len(data)} bytes")


def signing_timestamp(unix_time: float | None = None) -> int:
    """The signing timestamp of a unix time.

    Parameters
    ----------
    unix_time : float, optional
        Unix time, s; default now.

    Returns
    -------
    int
        Timestamp in 10 us units since 2015-01-01 UTC (0 before it).
    """
    now = time.time() if unix_time is None else unix_time
    return int(max(now - SIGNING_EPOCH_UNIX, 0.0) * 100_000)


def setup_outgoing(mav, key: bytes, link_id: int = 0) -> None:
    """Sign every packet a pymavlink ``MAVLink`` encoder packs from now on.

    Parameters
    ----------
    mav : pymavlink.dialects.v20.ardupilotmega.MAVLink
        The encoder.
    key : bytes
        The 32-byte signing key.
    link_id : int, optional
        MAVLink 2 signing link id. Default 0.
    """
    mav.signing.secret_key = key
    mav.signing.sign_outgoing = True
    mav.signing.link_id = link_id
    mav.signing.timestamp = signing_timestamp()


def signature_valid(raw: bytes, key: bytes) -> bool:
    """Whether a signed MAVLink 2 frame's signature matches ``key``.

    Parameters
    ----------
    raw : bytes
        The whole frame, signature included.
    key : bytes
        The 32-byte signing key.

    Returns
    -------
    bool
        False also for a frame that is too short or not signed.
    """
    if len(raw) < 12 + SIGNATURE_BYTES or not raw[2] & _SIGNED_FLAG:
        return False
    digest = hashlib.sha256(key + bytes(raw[:-6])).digest()[:6]
    return digest == bytes(raw[-6:])


@dataclass
class SenderFilter:
    """Accepts packets from the ground station only: its system id, its component id
    (None = any component of that system) and, with a key, a valid signature whose
    timestamp is newer than the last accepted on its stream (a new stream: at most 60 s
    behind the receiver's clock). Counts what it refuses. With ``state`` (a file path) the
    last timestamps are read from it at the start and written back by :meth:`save`."""

    ground_system: int = 255
    ground_component: int | None = None
    key: bytes | None = None
    accepted: int = 0
    rejected: dict[str, int] = field(default_factory=dict)
    state: str | Path | None = None
    _last: dict[tuple[int, int, int], int] = field(default_factory=dict, repr=False)
    _saved: float = field(default=0.0, repr=False)
    _dirty: bool = field(default=False, repr=False)

    def __post_init__(self) -> None:
        if not 1 <= self.ground_system <= 255:
            raise ValueError(f"ground system id must be 1..255, got {self.ground_system}")
        if self.ground_component is not None and not 0 <= self.ground_component <= 255:
            raise ValueError(f"ground component id must be 0..255, got "
                             f"{self.ground_component}")
        if self.key is not None and len(self.key) != KEY_BYTES:
            raise ValueError(f"a signing key has {KEY_BYTES} bytes, got {len(self.key)}")
        if self.state is not None:
            self._last.update(read_state(self.state))
            self._saved = time.monotonic()

    def clock(self) -> int:
        """The receiver's signing clock: the larger of the wall clock and the newest
        timestamp accepted (10 us units since 2015-01-01)."""
        return max(signing_timestamp(), max(self._last.values(), default=0))

    def reason(self, raw: bytes, source: tuple[int, int]) -> str | None:
        """Why a frame from ``source`` (sysid, compid) is refused, or None to accept it."""
        sysid, compid = source
        if sysid != self.ground_system or (self.ground_component is not None
                                           and compid != self.ground_component):
            return "other sender"
        if self.key is None:
            return None
        if raw[0] != 0xFD or not raw[2] & _SIGNED_FLAG:
            return "unsigned"
        if not signature_valid(raw, self.key):
            return "bad signature"
        stream = (raw[-13], sysid, compid)
        stamp = int.from_bytes(raw[-12:-6], "little")
        if stream in self._last:
            if stamp <= self._last[stream]:
                return "replayed"
        elif stamp + NEW_STREAM_WINDOW < self.clock():
            return "stale"
        self._last[stream] = stamp
        self._dirty = True
        return None

    def refuse(self, why: str) -> None:
        """Count a packet refused for ``why`` after it passed :meth:`reason`."""
        self.rejected[why] = self.rejected.get(why, 0) + 1

    def save(self, force: bool = True) -> None:
        """Write the last timestamps to the state file (if any); without ``force`` at most
        once per ``SAVE_INTERVAL_S``."""
        if self.state is None or not self._dirty:
            return
        if not force and time.monotonic() - self._saved < SAVE_INTERVAL_S:
            return
        write_state(self.state, self._last)
        self._saved, self._dirty = time.monotonic(), False

    def accept(self, raw: bytes, source: tuple[int, int]) -> bool:
        """Check one frame and count it; True if it may command the aircraft."""
        why = self.reason(raw, source)
        if why is None:
            self.accepted += 1
            self.save(force=False)
            return True
        self.refuse(why)
        return False
