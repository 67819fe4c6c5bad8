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
from flightid.sim.model import load

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
    error leaves no partial tlog and an existing file untouched."""
    tlog_path = Path(tlog_path)
    with atomic_path(tlog_path) as tmp:
        report = _record_into(link, tlog_path, tmp, duration, idle_timeout, first_timeout,
                              on_frame, stop)
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


def decode_tlog(path: str | Path, servo_map: ServoMap | None = None) -> TlogData:
    """Every packet of a tlog decoded to canonical channels, grouped by source and message."""
    servo_map = servo_map or ServoMap()
    tr = read_tlog(path)
    raw: dict[tuple[Source, str, str], tuple[list[float], list[float]]] = {}
    sync: dict[Source, tuple[list[float], list[float]]] = {}
    counts: dict[Source, dict[str, int]] = {}
    packets = []
    for e in tr.entries:
        msg, src = e.frame.msg, e.frame.source
        kind = msg.get_type()
        t = message_time(msg)
        packets.append((src, msg.get_seq(), t))
        c = counts.setdefault(src, {})
        c[kind] = c.get(kind, 0) + 1
        if kind == "SYSTEM_TIME":
            if msg.time_unix_usec > 0:
                s = sync.setdefault(src, ([], []))
                s[0].append(msg.time_unix_usec * 1e-6)
                s[1].append(msg.time_boot_ms * 1e-3)
            continue
        if t is None:
            continue
        for ch, v in decode(msg, servo_map).items():
            ts, vs = raw.setdefault((src, kind, ch), ([], []))
            ts.append(t)
            vs.append(v)
    series = {}
    for key, (ts, vs) in raw.items():
        t_arr, v_arr = np.array(ts), np.array(vs)
        order = np.argsort(t_arr, kind="stable")
        t_arr, v_arr = t_arr[order], v_arr[order]
        keep = np.concatenate([[True], np.diff(t_arr) > 0])  # one value per time stamp
        series[key] = Series(key[0], key[1], t_arr[keep], v_arr[keep])
    return TlogData(
        series, {s: (np.array(a), np.array(b)) for s, (a, b) in sync.items()},
        sequence_losses(packets), counts, tr.notes, tr.truncated_bytes, tr.skipped_bytes,
        len(tr.entries),
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


def _grid_rate(times: list[np.ndarray]) -> float:
    """Rate (Hz, to 1 mHz) of the most densely sampled series (times on the reference clock)."""
    fastest = max(times, key=lambda t: len(t) / max(float(np.ptp(t)), 1e-9))
    return round(1.0 / float(np.median(np.diff(fastest))), 3)


def convert_tlog(
    path: str | Path, *, servo_map: ServoMap | None = None, align: str = "auto",
    reference: str | None = None, rate: float | None = None, aircraft: str = "",
    max_offset: float = 10.0,
) -> FlightRecord:
    """A tlog as a FlightRecord: canonical SI channels, clocks aligned, uniform time base.

    reference: 'sysid/compid' of the clock to use (default: the source sending
    HIGHRES_IMU, else the busiest); rate: output rate in Hz (default: the fastest
    channel's). Each channel comes from the source and message that carried it most often.
    """
    data = decode_tlog(path, servo_map)
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
    fs = rate or _grid_rate([t for _, t in chosen.values()])
    if fs <= 0:
        raise ValueError(f"output rate must be > 0 Hz, got {fs}")
    # the grid spans the fastest channel (on the reference clock)
    fastest = max(chosen.values(), key=lambda c: len(c[1]))[1]
    n = int(np.floor((fastest[-1] - fastest[0]) * fs + 1e-6)) + 1
    grid = fastest[0] + np.arange(n) / fs
    out, held, gaps, sources = {}, {}, {}, {}
    for ch, (ser, t) in sorted(chosen.items()):
        v = np.unwrap(ser.v) if ch == "psi" else ser.v
        out[ch] = np.interp(grid, t, v)
        held[ch] = int(np.sum((grid < t[0]) | (grid > t[-1])))
        gaps[ch] = float(np.max(np.diff(t))) if len(t) > 1 else 0.0
        sources[ch] = ser.label
    extra = {
        "bridge": {
            "tlog": str(path),
            "reference_source": source_name(ref),
            "alignment": {source_name(s): m.as_dict() for s, m in maps.items()},
            "resampling": {
                "method": "linear interpolation (numpy.interp) of each channel from its own "
                          "message time stamps, mapped to the reference clock, onto a uniform "
                          f"grid at {fs:g} Hz spanning the fastest channel; psi unwrapped "
                          "before interpolation; values outside a channel's own span held",
                "rate_hz": fs,
                "held_samples": held,
                "max_gap_s": gaps,
            },
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
