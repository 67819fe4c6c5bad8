"""Links that carry the bridge's bytes, and the faults a real link adds.

Transports: a serial device by name (pyserial), a pseudo-terminal pair (``os.openpty``;
the bridge writes the master end, a recorder opens the slave device by name as it would
a real serial port), and UDP datagrams on the loopback interface only.

Faults (seeded RNG, applied by :class:`Transmitter` on the air side):
- ``drop``: probability that a whole packet is lost;
- ``corrupt``: probability that each byte is corrupted (XOR with a random non-zero
  byte), independently, so a packet of n bytes survives with probability (1 - corrupt)^n;
- ``latency`` (s) and ``jitter`` (s, standard deviation of a Gaussian, truncated so that
  no packet arrives before it was sent): delivery delay, applied in real time only.
Packets leave in order (a serial line cannot reorder): delivery times never decrease.
A UART model sends n bytes in 10 n / baud seconds; a packet that would wait for more than
``buffer_bytes`` of backlog is lost to overflow.
"""

from __future__ import annotations

import errno
import ipaddress
import os
import select
import socket
import threading
import time
import tty
from collections import deque
from dataclasses import asdict, dataclass, field

import numpy as np
import serial


@dataclass(frozen=True)
class LinkFaults:
    """Injected link faults: probabilities per packet (drop) / per byte (corrupt), seconds."""

    corrupt: float = 0.0
    drop: float = 0.0
    latency: float = 0.0
    jitter: float = 0.0

    def __post_init__(self) -> None:
        for name in ("corrupt", "drop"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"fault {name}={v}: a probability must lie in [0, 1]")
        for name in ("latency", "jitter"):
            if getattr(self, name) < 0:
                raise ValueError(f"fault {name}={getattr(self, name)} s must be >= 0")

    @classmethod
    def parse(cls, text: str) -> LinkFaults:
        """From ``"corrupt=0.1,drop=0.05,latency=0.02,jitter=0.01"`` (any subset)."""
        values: dict[str, float] = {}
        for item in filter(None, (p.strip() for p in text.split(","))):
            key, sep, val = item.partition("=")
            key = key.strip()
            if not sep:
                raise ValueError(f"fault {item!r}: expected name=value")
            if key not in cls.__dataclass_fields__:
                raise ValueError(
                    f"unknown fault {key!r}; known: {', '.join(cls.__dataclass_fields__)}"
                )
            try:
                values[key] = float(val)
            except ValueError:
                raise ValueError(f"fault {key}: {val!r} is not a number") from None
        return cls(**values)

    @property
    def damaging(self) -> bool:
        """Whether packets can be lost or altered."""
        return self.corrupt > 0 or self.drop > 0


# -- transports -------------------------------------------------------------------------


class Link:
    """Byte or datagram transport: write, read with a timeout, close."""

    datagrams = False

    def write(self, data: bytes) -> None:
        """Send bytes (one datagram for datagram links)."""
        raise NotImplementedError

    def read(self, timeout: float) -> bytes | None:
        """Bytes received within ``timeout`` s: b"" on timeout, None at end of stream."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the transport."""


class FdLink(Link):
    """A raw file descriptor (the master end of a pty)."""

    def __init__(self, fd: int, name: str = "") -> None:
        self.fd, self.name = fd, name

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            n = os.write(self.fd, view)
            view = view[n:]

    def read(self, timeout: float) -> bytes | None:
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if not ready:
            return b""
        try:
            data = os.read(self.fd, 65536)
        except OSError:  # EIO: the other end of the pty is closed
            return None
        return data or None

    def close(self) -> None:
        try:
            os.close(self.fd)
        except OSError:
            pass


class SerialLink(Link):
    """A serial device by name (a real UART, a USB adapter, or a pty slave) via pyserial."""

    def __init__(self, port: str, baud: int = 57600) -> None:
        try:
            self.port = serial.Serial(port, baud, timeout=0)
        except serial.SerialException as exc:
            raise OSError(f"cannot open serial port {port!r} at {baud} baud: {exc}") from None
        self.name = port

    def write(self, data: bytes) -> None:
        self.port.write(data)

    def read(self, timeout: float) -> bytes | None:
        try:
            ready, _, _ = select.select([self.port.fileno()], [], [], timeout)
            if not ready:
                return b""
            data = os.read(self.port.fileno(), 65536)
        except (OSError, serial.SerialException):
            return None  # device gone (pty master closed, adapter unplugged)
        return data or None

    def close(self) -> None:
        self.port.close()


@dataclass
class PtyPair:
    """A pseudo-terminal: the bridge writes ``master``; ``slave_path`` is the device name."""

    master: int
    slave: int
    slave_path: str

    def master_link(self) -> FdLink:
        """The master end as a link."""
        return FdLink(self.master, f"pty master of {self.slave_path}")

    def close(self) -> None:
        """Close both ends (the slave is held open so early bytes are not lost)."""
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


def open_pty_pair() -> PtyPair:
    """A pty in raw mode (no echo, no line editing: binary-safe) and its device name.

    Returns
    -------
    PtyPair
        Master and slave file descriptors and the slave's device path.
    """
    master, slave = os.openpty()
    tty.setraw(slave)
    tty.setraw(master)
    return PtyPair(master, slave, os.ttyname(slave))


def _loopback(host: str) -> str:
    try:
        addr = socket.gethostbyname(host)
    except OSError:
        raise ValueError(f"UDP host {host!r} does not resolve") from None
    if not ipaddress.ip_address(addr).is_loopback:
        raise ValueError(
            f"UDP host {host!r} ({addr}) is not a loopback address; the bridge only "
            "talks to 127.0.0.0/8"
        )
    return addr


def parse_hostport(text: str) -> tuple[str, int]:
    """``"127.0.0.1:14550"`` -> (address, port), loopback only.

    Parameters
    ----------
    text : str
        ``HOST:PORT``; an empty host means 127.0.0.1.

    Returns
    -------
    tuple of (str, int)
        Loopback address and UDP port (1..65535).

    Raises
    ------
    ValueError
        Naming ``text`` when it is malformed, the port is out of range or the host is not
        loopback.
    """
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit():
        raise ValueError(f"expected HOST:PORT (e.g. 127.0.0.1:14550), got {text!r}")
    if not 1 <= int(port) <= 65535:
        raise ValueError(f"UDP port {int(port)} in {text!r} is outside 1..65535")
    return _loopback(host or "127.0.0.1"), int(port)


class UdpLink(Link):
    """UDP on loopback: ``listen`` binds (a ground station); otherwise sends to ``peer``.

    A listening link replies to the last address it heard from (as mavutil's udpin).
    """

    datagrams = True

    def __init__(self, address: tuple[str, int], listen: bool) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 * 1024 * 1024)
        self.peer: tuple[str, int] | None = None
        host, port = address
        if listen:
            try:
                self.sock.bind((_loopback(host), port))
            except OSError as exc:
                self.sock.close()
                why = (f"port {port} on {_loopback(host)} is in use (another recorder or "
                       "ground station listens there)" if exc.errno == errno.EADDRINUSE
                       else f"cannot listen on port {port} of {_loopback(host)}: "
                            f"{(exc.strerror or str(exc)).lower()}")
                new = OSError(why)
                new.errno = exc.errno
                raise new from None
        else:
            self.sock.bind(("127.0.0.1", 0))
            self.peer = (_loopback(host), port)
        self.name = f"udp {'in' if listen else 'out'} {host}:{port}"

    @property
    def local_address(self) -> tuple[str, int]:
        """(host, port) the socket is bound to."""
        return self.sock.getsockname()

    def write(self, data: bytes) -> None:
        if self.peer is None:
            return  # nobody to talk to yet
        self.sock.sendto(data, self.peer)

    def read(self, timeout: float) -> bytes | None:
        ready, _, _ = select.select([self.sock], [], [], timeout)
        if not ready:
            return b""
        data, addr = self.sock.recvfrom(65536)
        self.peer = addr
        return data

    def close(self) -> None:
        self.sock.close()


# -- the air side's transmitter ---------------------------------------------------------


@dataclass
class PacketFate:
    """What happened to one packet the air side produced."""

    source: tuple[int, int]
    seq: int
    msgid: int
    t: float
    fate: str  # 'sent', 'corrupted', 'dropped', 'overflow'
    arrive: float = float("nan")  # modelled arrival (sim s) of what was sent


@dataclass
class TransmitReport:
    """Counts of what the transmitter did (air side's view of the link)."""

    packets: int = 0
    sent_intact: int = 0
    corrupted: int = 0
    dropped: int = 0
    overflow: int = 0
    bytes_offered: int = 0
    bytes_corrupted: int = 0
    max_queue_s: float = 0.0
    fates: list[PacketFate] = field(default_factory=list, repr=False)

    def as_dict(self) -> dict:
        """Counts as plain data (without the per-packet list)."""
        d = asdict(self)
        d.pop("fates")
        return d


class Transmitter:
    """Sends packets through faults and a UART model onto a link, in order.

    ``send`` is called with the sim time of each packet. In real time a writer thread
    delivers each packet at its modelled arrival time (sim time mapped to the wall clock
    at ``start``); otherwise packets are written at once (the model still decides losses).
    """

    def __init__(
        self, link: Link, faults: LinkFaults, baud: int | None, seed: int,
        realtime: bool = False, buffer_bytes: int = 4096, keep_fates: bool = True,
    ) -> None:
        self.link, self.faults, self.baud = link, faults, baud
        self.rng = np.random.default_rng(seed)
        self.realtime, self.buffer_bytes, self.keep_fates = realtime, buffer_bytes, keep_fates
        self.report = TransmitReport()
        self._line_free = 0.0  # sim time the UART finishes its backlog
        self._last_delivery = 0.0
        self._queue: deque[tuple[float, bytes]] = deque()
        self._cv = threading.Condition()
        self._closing = False
        self._t0_wall: float | None = None
        self._thread: threading.Thread | None = None
        self.error: BaseException | None = None

    def start(self, t_sim: float = 0.0) -> None:
        """Anchor sim time ``t_sim`` to now and, in real time, start the writer thread."""
        self._t0_wall = time.monotonic() - t_sim
        if self.realtime and self._thread is None:
            self._thread = threading.Thread(target=self._writer, daemon=True)
            self._thread.start()

    def delivery_time(self, t: float, nbytes: int) -> float | None:
        """Modelled arrival time (sim s) of a packet of nbytes offered at t; None = overflow."""
        start = max(t, self._line_free)
        if self.baud:
            backlog = (self._line_free - t) * self.baud / 10.0
            if backlog + nbytes > self.buffer_bytes:
                return None
            self._line_free = start + nbytes * 10.0 / self.baud
            self.report.max_queue_s = max(self.report.max_queue_s, start - t)
        else:
            self._line_free = start
        arrive = self._line_free + self.faults.latency
        if self.faults.jitter > 0:
            arrive = max(self._line_free, arrive + self.rng.normal(0.0, self.faults.jitter))
        arrive = max(arrive, self._last_delivery)
        self._last_delivery = arrive
        return arrive

    def send(self, packet: bytes, t: float, source: tuple[int, int], seq: int, msgid: int) -> str:
        """Offer one packet at sim time t (s); returns its fate."""
        rep = self.report
        rep.packets += 1
        rep.bytes_offered += len(packet)
        arrive = float("nan")
        if self.faults.drop and self.rng.random() < self.faults.drop:
            fate = "dropped"
        else:
            arrive = self.delivery_time(t, len(packet))
            if arrive is None:
                fate, arrive = "overflow", float("nan")
            else:
                fate = "sent"
                if self.faults.corrupt:
                    hit = self.rng.random(len(packet)) < self.faults.corrupt
                    if hit.any():
                        buf = np.frombuffer(packet, dtype=np.uint8).copy()
                        buf[hit] ^= self.rng.integers(1, 256, hit.sum(), dtype=np.uint8)
                        packet = buf.tobytes()
                        rep.bytes_corrupted += int(hit.sum())
                        fate = "corrupted"
                self._deliver(arrive, packet)
        if fate == "sent":
            rep.sent_intact += 1
        else:
            setattr(rep, fate, getattr(rep, fate) + 1)
        if self.keep_fates:
            rep.fates.append(PacketFate(source, seq, msgid, t, fate, arrive))
        return fate

    def _deliver(self, arrive: float, packet: bytes) -> None:
        if not self.realtime:
            self.link.write(packet)
            return
        if self.error is not None:
            raise self.error
        with self._cv:
            self._queue.append((arrive, packet))
            self._cv.notify()

    def _writer(self) -> None:
        try:
            while True:
                with self._cv:
                    while not self._queue and not self._closing:
                        self._cv.wait()
                    if not self._queue:
                        return
                    arrive, packet = self._queue[0]
                delay = self._t0_wall + arrive - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                with self._cv:
                    self._queue.popleft()
                self.link.write(packet)
        except BaseException as exc:  # reported to the sender thread
            self.error = exc

    def wall_time(self, t: float) -> float:
        """Monotonic wall-clock time at which sim time t (s) falls, in real time."""
        return self._t0_wall + t

    def close(self) -> None:
        """Deliver what is queued, then stop the writer thread."""
        with self._cv:
            self._closing = True
            self._cv.notify()
        if self._thread is not None:
            self._thread.join()
        if self.error is not None:
            raise self.error
