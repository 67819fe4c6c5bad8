"""The ground side of the recorder bridge: record a MAVLink stream, convert tlogs.

``record_stream`` reads bytes from a link (serial device, pty, loopback UDP), keeps every
intact packet (``frames.FrameScanner``), writes them to a standard .tlog and a
``<tlog>.json`` report (corrupt frames, junk bytes, sequence losses).
``convert_tlog`` turns a tlog into a FlightRecord: canonical channels in SI
(``messages.decode``), separately clocked recorders aligned to the reference
recorder's clock (``align``), and every channel resampled onto one uniform time
base by linear interpolation (the method and its details are stated in the metadata).

Lost packets are counted from MAVLink sequence numbers per (sysid, compid). A sequence
number has 8 bits, so a gap of more than 255 packets wraps; gaps are unwrapped with the
source's own time stamps and its mean packet rate (the wrap count closest to rate * dt).
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flightid.files import atomic_path, write_text
from flightid.record import FlightRecord, RecordMeta
from flightid.sim.bridge.air import BridgeConfig, serve_record
from flightid.sim.bridge.align import ClockMap, timesync_map, xcorr_map
from flightid.sim.bridge.frames import Frame, FrameScanner, TlogWriter, read_tlog
from flightid.sim.bridge.link import Link, SerialLink, UdpLink, open_pty_pair
from flightid.sim.bridge.messages import CHANNEL_SOURCES, ServoMap, decode, message_time
from flightid.sim.jsbsim.model import load

Source = tuple[int, int]


def source_name(src: Source) -> str:
    """'sysid/compid'."""
    return f"{src[0]}/{src[1]}"


@dataclass
class SourceLoss:
    """Packets received from one source and packets missing between them."""

    received: int = 0
    lost: int = 0
    wraps: int = 0  # gaps longer than 255 packets found by the time stamps

    @property
    def loss_rate(self) -> float:
        """lost / (received + lost)."""
        total = self.received + self.lost
        return self.lost / total if total else 0.0


def sequence_losses(packets: list[tuple[Source, int, float | None]]) -> dict[Source, SourceLoss]:
    """Per source, packets lost between the first and last received (seq gaps).

    ``packets``: (source, seq, message time or None) in arrival order. Between two
    received packets that carry time stamps, the number of 256-packet wraps is the one
    that brings the sequence advance closest to (mean packet rate) * (time between them).
    """
    by_src: dict[Source, list[tuple[int, float]]] = {}
    for src, seq, t in packets:
        by_src.setdefault(src, []).append((seq, np.nan if t is None else t))
    out = {}
    for src, items in by_src.items():
        seq = np.array([s for s, _ in items])
        t = np.array([x for _, x in items], dtype=float)
        adv = (np.diff(seq) % 256).astype(float)
        adv[adv == 0] = 256.0  # same seq again: a full wrap (as mavutil counts it)
        timed = np.flatnonzero(np.isfinite(t))
        wraps = 0
        if len(timed) >= 2:
            # advance and elapsed time between consecutive time-stamped packets
            seg_adv = np.array([adv[a:b].sum() for a, b in zip(timed[:-1], timed[1:],
                                                                strict=True)])
            seg_dt = np.diff(t[timed])
            for _ in range(2):  # the rate from the unwrapped advances, then once more
                pos = seg_dt > 0
                if not pos.any() or seg_dt[pos].sum() <= 0:
                    break
                rate = seg_adv.sum() / seg_dt[pos].sum()
                k = np.where(pos, np.round((rate * seg_dt - seg_adv) / 256.0), 0.0)
                k = np.maximum(k, 0.0)
                seg_adv = seg_adv + 256.0 * k
                wraps += int(k.sum())
            total = seg_adv.sum() + adv[: timed[0]].sum() + adv[timed[-1]:].sum()
        else:
            total = adv.sum()
        out[src] = SourceLoss(len(items), int(total - (len(items) - 1)), wraps)
    return out


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


def _loss_dict(losses: dict[Source, SourceLoss]) -> dict[str, dict]:
    return {source_name(s): {"received": v.received, "lost": v.lost, "loss_rate": v.loss_rate,
                             "wraps": v.wraps} for s, v in sorted(losses.items())}


def record_stream(
    link: Link, tlog_path: str | Path, *, duration: float | None = None,
    idle_timeout: float = 5.0, first_timeout: float = 30.0, on_frame=None,
    stop: threading.Event | None = None,
) -> RecordingReport:
    """Record intact packets from ``link`` into a .tlog until ``duration`` s have passed,
    the stream ends, nothing arrives for ``idle_timeout`` s (``first_timeout`` s before
    the first byte), or ``stop`` is set and nothing is pending. Writes ``<tlog>.json``.

    The tlog is written to a temporary file beside ``tlog_path`` and moved there when the
    recording ends (also when it is interrupted: the packets recorded so far are kept); an
    error leaves no partial tlog and an existing file untouched. A recording without a
    single intact packet raises TimeoutError and writes nothing."""
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
        _loss_dict(sequence_losses(packets)), ended,
    )


# -- tlog -> FlightRecord ------------------------------------------------------------------


@dataclass
class Series:
    """One channel as one message of one source carried it: times on the source clock."""

    source: Source
    message: str
    t: np.ndarray
    v: np.ndarray

    @property
    def label(self) -> str:
        """'sysid/compid MESSAGE'."""
        return f"{source_name(self.source)} {self.message}"


@dataclass
class TlogData:
    """Decoded tlog: per-source series, time-sync pairs, losses, read problems."""

    series: dict[tuple[Source, str, str], Series]  # (source, message, channel)
    timesync: dict[Source, tuple[np.ndarray, np.ndarray]]  # common unix s, local s
    losses: dict[Source, SourceLoss]
    counts: dict[Source, dict[str, int]]
    read_notes: list[str]
    truncated_bytes: int
    skipped_bytes: int
    packets: int
    untimed: dict[str, dict] = field(default_factory=dict)  # message -> timing from neighbours
    reversals: list[TimeReversal] = field(default_factory=list)


@dataclass(frozen=True)
class TimeReversal:
    """A message type of one source whose time stamp went back (s, the source's clock)."""

    source: Source
    message: str
    packet: int  # index of the packet in the tlog
    before: float
    after: float

    def describe(self) -> str:
        """'1/1 HIGHRES_IMU went back from 45.000 s to 0.000 s at packet 4271'."""
        return (f"{source_name(self.source)} {self.message} went back from {self.before:.3f} s "
                f"to {self.after:.3f} s at packet {self.packet}")


#: a message type's time may go back this much (s) before it counts as a time reversal
REVERSAL_TOLERANCE = 1e-3
#: a message without a time field is timed from its source's neighbouring time-stamped
#: messages only when they lie within this many seconds of each other
UNTIMED_WINDOW = 0.5


def cadence_times(brackets: list[tuple[float, float, object]]) -> list[float]:
    """Times (s) of messages without a time field, each known to lie in [t_prev, t_next]
    (its neighbouring time-stamped messages): t_prev where the bracket is closed; else the
    end of the bracket that keeps the message's own cadence (whole intervals from the last
    closed bracket before it, the interval being the shortest step between consecutive
    closed brackets), t_prev when neither does or the cadence is unknown."""
    exact = [i for i, (a, b, _) in enumerate(brackets) if b - a <= REVERSAL_TOLERANCE]
    times = [a for a, _, _ in brackets]
    steps = [brackets[j][0] - brackets[i][0] for i, j in zip(exact[:-1], exact[1:],
                                                              strict=True) if j == i + 1]
    steps = [d for d in steps if d > REVERSAL_TOLERANCE]
    if not steps:
        return times
    dt = min(steps)
    anchor = None
    for i, (a, b, _) in enumerate(brackets):
        if b - a <= REVERSAL_TOLERANCE:
            anchor = a
            continue
        if anchor is None:
            continue
        miss = [abs((x - anchor) / dt - round((x - anchor) / dt)) for x in (a, b)]
        if miss[1] < miss[0] - 1e-6:
            times[i] = b
    return times


def decode_tlog(path: str | Path, servo_map: ServoMap | None = None,
                untimed_window: float = UNTIMED_WINDOW) -> TlogData:
    """Every packet of a tlog decoded to canonical channels, grouped by source and message.

    A message without a time field (VFR_HUD) takes the time of the last time-stamped
    message of its source before it in the tlog: a sender sends a message after the
    samples it reports, and a recorder keeps the order. The next time-stamped message of
    the source bounds the error; a message whose neighbours are more than
    ``untimed_window`` s apart (a gap in the stream) is left out and counted. A message
    type whose time goes back (a tlog holding two recordings, a reset clock) is listed in
    ``reversals``.
    """
    servo_map = servo_map or ServoMap()
    tr = read_tlog(path)
    raw: dict[tuple[Source, str, str], tuple[list[float], list[float]]] = {}
    sync: dict[Source, tuple[list[float], list[float]]] = {}
    counts: dict[Source, dict[str, int]] = {}
    packets = []
    last_timed: dict[Source, float] = {}
    waiting: dict[Source, list[tuple[str, float, dict[str, float]]]] = {}
    untimed: dict[str, dict] = {}
    last_of_kind: dict[tuple[Source, str], float] = {}
    reversals: list[TimeReversal] = []

    def keep(src: Source, kind: str, t: float, values: dict[str, float]) -> None:
        for ch, v in values.items():
            ts, vs = raw.setdefault((src, kind, ch), ([], []))
            ts.append(t)
            vs.append(v)

    bracketed: dict[tuple[Source, str], list[tuple[float, float, dict[str, float]]]] = {}

    def settle(src: Source, t_next: float | None) -> None:
        """Bracket the messages waiting for the next time-stamped message of ``src``."""
        for kind, t_prev, values in waiting.pop(src, []):
            u = untimed.setdefault(kind, {"timed": 0, "left_out": 0, "max_bracket_s": 0.0})
            width = 0.0 if t_next is None else t_next - t_prev
            if not -REVERSAL_TOLERANCE <= width <= untimed_window:
                u["left_out"] += 1
                continue
            u["timed"] += 1
            u["max_bracket_s"] = max(u["max_bracket_s"], width)
            bracketed.setdefault((src, kind), []).append(
                (t_prev, t_prev + max(width, 0.0), values))

    for index, e in enumerate(tr.entries):
        msg, src = e.frame.msg, e.frame.source
        kind = msg.get_type()
        t = message_time(msg)
        packets.append((src, msg.get_seq(), t))
        c = counts.setdefault(src, {})
        c[kind] = c.get(kind, 0) + 1
        if t is not None:
            before = last_of_kind.get((src, kind))
            if before is not None and t < before - REVERSAL_TOLERANCE:
                reversals.append(TimeReversal(src, kind, index, before, t))
            last_of_kind[(src, kind)] = t
            if src in waiting:
                settle(src, t)
            last_timed[src] = t
        if kind == "SYSTEM_TIME":
            if msg.time_unix_usec > 0:
                s = sync.setdefault(src, ([], []))
                s[0].append(msg.time_unix_usec * 1e-6)
                s[1].append(msg.time_boot_ms * 1e-3)
            continue
        values = decode(msg, servo_map)
        if not values:
            continue
        if t is not None:
            keep(src, kind, t, values)
        elif src in last_timed:
            waiting.setdefault(src, []).append((kind, last_timed[src], values))
        else:
            u = untimed.setdefault(kind, {"timed": 0, "left_out": 0, "max_bracket_s": 0.0})
            u["left_out"] += 1  # before any time-stamped message of its source
    for src in list(waiting):
        settle(src, None)
    for (src, kind), items in bracketed.items():
        for t, values in zip(cadence_times(items), items, strict=True):
            keep(src, kind, t, values[2])
    series = {}
    for key, (ts, vs) in raw.items():
        t_arr, v_arr = np.array(ts), np.array(vs)
        order = np.argsort(t_arr, kind="stable")
        t_arr, v_arr = t_arr[order], v_arr[order]
        keep_one = np.concatenate([[True], np.diff(t_arr) > 0])  # one value per time stamp
        series[key] = Series(key[0], key[1], t_arr[keep_one], v_arr[keep_one])
    return TlogData(
        series, {s: (np.array(a), np.array(b)) for s, (a, b) in sync.items()},
        sequence_losses(packets), counts, tr.notes, tr.truncated_bytes, tr.skipped_bytes,
        len(tr.entries), untimed, reversals,
    )


def _reference(data: TlogData, reference: str | None) -> Source:
    sources = list(data.counts)
    if not sources:
        raise ValueError("the tlog holds no intact MAVLink packet")
    if reference:
        for s in sources:
            if source_name(s) == reference:
                return s
        raise ValueError(f"reference source {reference!r} not in the tlog; it has "
                         f"{', '.join(source_name(s) for s in sources)}")
    with_imu = [s for s in sources if "HIGHRES_IMU" in data.counts[s]]
    pool = with_imu or sources
    return max(pool, key=lambda s: (sum(data.counts[s].values()), -s[0], -s[1]))


def _channel_series(data: TlogData, src: Source) -> dict[str, Series]:
    """The best series per channel of one source (most samples, then preference)."""
    best: dict[str, Series] = {}
    for (s, msg, ch), ser in data.series.items():
        if s != src:
            continue
        pref = CHANNEL_SOURCES.get(ch, ())
        rank = (len(ser.t), -pref.index(msg) if msg in pref else -99)
        cur = best.get(ch)
        if cur is None or rank > (len(cur.t), -pref.index(cur.message) if cur.message in pref
                                  else -99):
            best[ch] = ser
    return best


def align_sources(
    data: TlogData, reference: Source, method: str = "auto", max_offset: float = 10.0,
) -> dict[Source, ClockMap]:
    """Clock map of every source onto the reference source's clock.

    method: 'timesync' (SYSTEM_TIME), 'xcorr' (a channel both streams carry), 'auto'
    (time sync where both streams have it, else cross-correlation), 'none'.
    """
    if method not in ("auto", "timesync", "xcorr", "none"):
        raise ValueError(f"unknown alignment method {method!r}; use auto, timesync, xcorr, none")
    maps = {reference: ClockMap()}
    todo = [s for s in data.counts if s != reference]
    if method == "none":
        return {**maps, **{s: ClockMap(method="none") for s in todo}}
    ref_sync = data.timesync.get(reference)
    channels = {s: _channel_series(data, s) for s in data.counts}
    errors: dict[Source, str] = {}
    progress = True
    while todo and progress:
        progress = False
        for src in list(todo):
            cmap = None
            src_sync = data.timesync.get(src)
            if method in ("auto", "timesync") and ref_sync is not None and src_sync is not None \
                    and len(ref_sync[0]) >= 2 and len(src_sync[0]) >= 2:
                cmap = timesync_map(src_sync[0], src_sync[1], ref_sync[0], ref_sync[1])
            elif method == "timesync":
                raise ValueError(f"source {source_name(src)} or the reference has no SYSTEM_TIME "
                                 "time-sync pairs; use --align xcorr")
            else:
                cmap, errors[src] = _xcorr_any(channels, src, maps, max_offset)
            if cmap is not None:
                maps[src] = cmap
                todo.remove(src)
                progress = True
    if todo:
        why = "; ".join(f"{source_name(s)}: {errors.get(s, 'no common channel')}" for s in todo)
        raise ValueError(f"cannot align sources to {source_name(reference)}: {why}")
    return maps


def _xcorr_any(channels, src, maps, max_offset) -> tuple[ClockMap | None, str]:
    """Cross-correlate src with any aligned source on the common channel that fits best."""
    best, err = None, "no channel in common with an aligned source"
    for other, omap in maps.items():
        common = set(channels[src]) & set(channels[other])
        for ch in sorted(common):
            a, b = channels[other][ch], channels[src][ch]
            if np.ptp(a.v) == 0 or np.ptp(b.v) == 0:
                continue
            try:
                m = xcorr_map(a.t, a.v, b.t, b.v, max_offset=max_offset,
                              via=f"{ch} ({a.label} vs {b.label})")
            except ValueError as exc:
                err = str(exc)
                continue
            # m maps src -> other; omap maps other -> reference
            full = m.then(omap) if omap.method != "reference" else m
            if best is None or full.sigma < best.sigma:
                best = full
    return best, ("" if best else err)


def nominal_interval(t: np.ndarray) -> float:
    """The interval (s) a series was sent at: its most frequent time step (to 0.1 ms; the
    smallest of equally frequent ones). With independent losses a step of k intervals
    has probability (1 - p) p^(k-1), largest at k = 1 whatever the loss rate p."""
    steps = np.round(np.diff(t), 4)
    steps = steps[steps > 0]
    if not steps.size:
        return float("inf")
    values, counts = np.unique(steps, return_counts=True)
    return float(values[np.argmax(counts)])


def _grid_rate(times: list[np.ndarray], intervals: list[float]) -> float:
    """Rate (Hz, to 1 mHz) of the most densely sampled series (times on the reference clock,
    their nominal intervals in s)."""
    usable = [i for i in range(len(times)) if len(times[i]) >= 2 and np.isfinite(intervals[i])]
    if not usable:
        return 0.0
    k = max(usable, key=lambda i: len(times[i]) / max(float(np.ptp(times[i])), 1e-9))
    return round(1.0 / intervals[k], 3)


@dataclass(frozen=True)
class Gap:
    """A stretch (s, reference clock) over which a channel has no sample for longer than
    the allowed number of its own sample intervals (``missing`` samples)."""

    channel: str
    start: float
    end: float
    missing: int

    def describe(self) -> str:
        """'V from 12.300 to 12.900 s (0.600 s, 14 samples missing)'."""
        return (f"{self.channel} from {self.start:.3f} to {self.end:.3f} s "
                f"({self.end - self.start:.3f} s, {self.missing} samples missing)")


#: default longest run of missing samples of a channel interpolated over (its own samples)
MAX_GAP_SAMPLES = 5
MIN_RECORD_SAMPLES = 10  # an output rate must give a record at least this long (samples)


def long_gaps(chosen: dict[str, np.ndarray], intervals: dict[str, float], start: float,
              end: float, max_gap: int) -> list[Gap]:
    """Gaps of more than ``max_gap`` missing samples (of each channel's nominal interval,
    s) in the channels' times ``chosen`` (s), including the ends of the span [start, end]."""
    out = []
    for ch, t in sorted(chosen.items()):
        dt = intervals[ch]
        if len(t) < 2 or not np.isfinite(dt):
            out.append(Gap(ch, start, end, -1))
            continue
        edges = np.concatenate([[min(start, t[0])], t, [max(end, t[-1])]])
        steps = np.diff(edges)
        missing = np.round(steps / dt).astype(int) - 1
        missing[0] += 1  # the ends: time before the first / after the last sample
        missing[-1] += 1
        for k in np.flatnonzero(missing > max_gap):
            out.append(Gap(ch, float(edges[k]), float(edges[k + 1]), int(missing[k])))
    return out


def longest_stretch(start: float, end: float, gaps: list[Gap]) -> tuple[float, float]:
    """The longest part of [start, end] (s) that no gap overlaps."""
    best, lo = (start, start), start
    for g in sorted(gaps, key=lambda g: g.start):
        if g.start > lo and g.start - lo > best[1] - best[0]:
            best = (lo, g.start)
        lo = max(lo, g.end)
    if end - lo > best[1] - best[0]:
        best = (lo, end)
    return best


SEGMENTS = ("all", "longest")


def convert_tlog(
    path: str | Path, *, servo_map: ServoMap | None = None, align: str = "auto",
    reference: str | None = None, rate: float | None = None, aircraft: str = "",
    max_offset: float = 10.0, max_gap: int = MAX_GAP_SAMPLES, segment: str = "all",
) -> FlightRecord:
    """A tlog as a FlightRecord: canonical SI channels, clocks aligned, uniform time base.

    reference: 'sysid/compid' of the clock to use (default: the source sending
    HIGHRES_IMU, else the busiest); rate: output rate in Hz (default: the fastest
    channel's). Each channel comes from the source and message that carried it most often.

    A record is never interpolated across more than ``max_gap`` missing samples of a
    channel (its own sample interval; the record's ends count too): such a gap is refused
    with ``segment='all'``, and ``segment='longest'`` keeps the longest stretch without
    one. A tlog whose time stamps go back (two recordings in one file, a reset clock) is
    refused. Raises ValueError (bad file) or FileNotFoundError.
    """
    if segment not in SEGMENTS:
        raise ValueError(f"segment {segment!r}: use one of {', '.join(SEGMENTS)}")
    if isinstance(max_gap, bool) or not isinstance(max_gap, int) or max_gap < 0:
        raise ValueError(f"max_gap must be a whole number of samples >= 0, got {max_gap!r}")
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"output rate must be > 0 Hz, got {rate}")
    data = decode_tlog(path, servo_map)
    if data.reversals:
        first = data.reversals[0]
        kinds = sorted({r.message for r in data.reversals if r.packet == first.packet
                        or abs(r.packet - first.packet) < 50})
        raise ValueError(
            f"{path}: time reversal: {first.describe()} ({len(data.reversals)} reversal(s) "
            f"in all; {', '.join(kinds)} go back there): the tlog holds more than one "
            "recording (files joined?) or the sender's clock was reset; split the file "
            "at that packet")
    ref = _reference(data, reference)
    maps = align_sources(data, ref, align, max_offset)
    chosen: dict[str, tuple[Series, np.ndarray]] = {}
    order = [ref] + [s for s in data.counts if s != ref]
    for src in order:
        for ch, ser in _channel_series(data, src).items():
            if ch in chosen and len(chosen[ch][0].t) >= len(ser.t):
                continue
            chosen[ch] = (ser, maps[src].to_reference(ser.t))
    if not chosen:
        raise ValueError(f"{path}: no message in the tlog carries a flight-record channel")
    intervals = {ch: nominal_interval(t) for ch, (_, t) in chosen.items()}
    fs = rate or _grid_rate([t for _, t in chosen.values()], [intervals[c] for c in chosen])
    if not fs > 0:
        raise ValueError(f"{path}: too few intact packets: no channel has two time-stamped "
                         "samples to find an output rate from")
    # the grid spans the fastest channel (on the reference clock)
    fastest = max(chosen.values(), key=lambda c: len(c[1]))[1]
    span = (float(fastest[0]), float(fastest[-1]))
    gaps_found = long_gaps({ch: t for ch, (_, t) in chosen.items()}, intervals, *span,
                           max_gap)
    if gaps_found and segment == "all":
        worst = sorted(gaps_found, key=lambda g: g.start - g.end)[:3]
        raise ValueError(
            f"{path}: {len(gaps_found)} gap(s) of more than {max_gap} missing samples, "
            f"the longest: {'; '.join(g.describe() for g in worst)}; a record is not "
            "interpolated across them: allow longer gaps (--max-gap) or keep the longest "
            "stretch without them (--segment longest)")
    lo, hi = longest_stretch(*span, gaps_found) if gaps_found else span
    n = int(np.floor((hi - lo) * fs + 1e-6)) + 1
    if rate is not None and n < MIN_RECORD_SAMPLES:
        raise ValueError(
            f"{path}: output rate (--rate) {fs:g} Hz gives {n} sample(s) over the "
            f"{hi - lo:.3g} s of the log; use at least {MIN_RECORD_SAMPLES / (hi - lo):.3g} Hz")
    if n < 2:
        raise ValueError(
            f"{path}: no stretch of two samples at {fs:g} Hz without a gap of more than "
            f"{max_gap} missing samples ({len(gaps_found)} gaps, e.g. "
            f"{gaps_found[0].describe()})")
    grid = lo + np.arange(n) / fs
    out, held, gaps, sources = {}, {}, {}, {}
    for ch, (ser, t) in sorted(chosen.items()):
        v = np.unwrap(ser.v) if ch == "psi" else ser.v
        out[ch] = np.interp(grid, t, v)
        if not np.all(np.isfinite(out[ch])):  # decode keeps finite values only
            raise ValueError(f"{path}: channel {ch} has non-finite values after resampling")
        held[ch] = int(np.sum((grid < t[0]) | (grid > t[-1])))
        inside = t[(t >= lo) & (t <= hi)]
        gaps[ch] = float(np.max(np.diff(inside))) if len(inside) > 1 else 0.0
        sources[ch] = ser.label
    extra = {
        "bridge": {
            "tlog": str(path),
            "reference_source": source_name(ref),
            "alignment": {source_name(s): m.as_dict() for s, m in maps.items()},
            "resampling": {
                "method": "linear interpolation (numpy.interp) of each channel from its own "
                          "message time stamps, mapped to the reference clock, onto a uniform "
                          f"grid at {fs:g} Hz spanning the fastest channel (or its longest "
                          "stretch without a long gap); psi unwrapped before interpolation; "
                          "values outside a channel's own span held (at most max_gap "
                          "samples)",
                "rate_hz": fs,
                "held_samples": held,
                "max_gap_s": gaps,
            },
            "gaps": {
                "max_gap_samples": max_gap,
                "segment": segment,
                "span_s": [lo, hi],
                "tlog_span_s": list(span),
                "found": [g.describe() for g in gaps_found],
            },
            "untimed_messages": data.untimed,
            "sources": sources,
            "losses": _loss_dict(data.losses),
            "packets": data.packets,
            "counts": {source_name(s): c for s, c in data.counts.items()},
            "truncated_bytes": data.truncated_bytes,
            "skipped_bytes": data.skipped_bytes,
            "read_notes": data.read_notes,
        }
    }
    side = Path(str(path) + ".json")
    if side.exists():
        try:
            extra["bridge"]["recording"] = json.loads(side.read_text())
        except json.JSONDecodeError as exc:
            extra["bridge"]["read_notes"].append(f"{side}: unreadable report ({exc})")
    meta = RecordMeta(
        aircraft=aircraft, sample_rate=fs,
        provenance=f"MAVLink tlog {path} converted by flightid.sim.bridge.recorder", extra=extra,
    )
    if aircraft:
        # MAVLink carries no mass properties or geometry: take them from the aircraft
        # definition, as a flight-test engineer takes them from the weight-and-balance sheet
        model = load(aircraft)
        meta.reference = model.reference
        out.update({k: np.full(grid.size, v) for k, v in model.mass_properties().items()})
        extra["bridge"]["a_priori"] = f"mass properties and reference geometry of {aircraft!r}"
    return FlightRecord(grid, out, meta)


def record_bridged(
    record: FlightRecord, tlog_path: str | Path, config=None, *, transport: str = "pty",
    port: int = 0,
):
    """Stream a record through the bridge to a recorder on this machine, over a pty pair
    (``transport='pty'``) or loopback UDP (``'udp'``, ``port`` 0 = any free port).

    Returns (air-side BridgeReport, ground-side RecordingReport); the tlog is written.
    """
    config = config or BridgeConfig()
    stop = threading.Event()
    result: dict = {}
    if transport == "pty":
        pty = open_pty_pair()
        ground: Link = SerialLink(pty.slave_path, config.baud or 115200)
        air: Link = pty.master_link()
        closers = [ground.close, pty.close]
    elif transport == "udp":
        ground = UdpLink(("127.0.0.1", port), listen=True)
        air = UdpLink(ground.local_address, listen=False)
        closers = [ground.close, air.close]
    else:
        raise ValueError(f"unknown transport {transport!r}; use 'pty' or 'udp'")

    def run_ground() -> None:
        try:
            result["ground"] = record_stream(ground, tlog_path, idle_timeout=30.0, stop=stop)
        except BaseException as exc:  # surfaced below
            result["error"] = exc

    thread = threading.Thread(target=run_ground, daemon=True)
    thread.start()
    try:
        air_report = serve_record(record, air, config)
    finally:
        stop.set()
        thread.join(60.0)
        for close in closers:
            close()
    if "error" in result:
        raise result["error"]
    if "ground" not in result:
        raise TimeoutError("the recorder did not finish within 60 s of the end of the stream")
    return air_report, result["ground"]
