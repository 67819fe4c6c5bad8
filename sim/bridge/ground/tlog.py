"""A .tlog as a FlightRecord: canonical channels in SI (``messages.decode``), separately
clocked recorders aligned to the reference recorder's clock (``align``), and every channel
resampled onto one uniform time base by linear interpolation (the method and its details
are stated in the metadata). Reading a tlog imports nothing of the air side.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.bridge.frames import read_tlog
from flightid.sim.bridge.ground.align import ClockMap, timesync_map, xcorr_map
from flightid.sim.bridge.ground.gaps import (
    MAX_GAP_SAMPLES,
    MIN_RECORD_SAMPLES,
    grid_rate,
    long_gaps,
    longest_stretch,
    nominal_interval,
)
from flightid.sim.bridge.ground.sources import (
    Source,
    SourceLoss,
    loss_dict,
    sequence_losses,
    source_name,
)
from flightid.sim.bridge.messages import CHANNEL_SOURCES, ServoMap, decode, message_time
from flightid.sim.jsbsim.model import load


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
    """Times of messages without a time field, each known to lie in [t_prev, t_next].

    The bracket is given by its neighbouring time-stamped messages. t_prev where the bracket
    is closed; else the end of the bracket that keeps the message's own cadence (whole
    intervals from the last closed bracket before it, the interval being the shortest step
    between consecutive closed brackets), t_prev when neither does or the cadence is unknown.

    Parameters
    ----------
    brackets : list of tuple
        (t_prev, t_next, payload) per message, s.

    Returns
    -------
    list of float
        One time per message, s.
    """
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

    Parameters
    ----------
    path : str or pathlib.Path
        The .tlog file.
    servo_map : ServoMap, optional
        Maps servo PWM to surface deflections; default ``ServoMap()``.
    untimed_window : float, optional
        Widest bracket for a message without a time field, s. Default ``UNTIMED_WINDOW``.

    Returns
    -------
    TlogData
        Per-source series (SI), time-sync pairs, losses and read problems.
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

    Parameters
    ----------
    data : TlogData
        The decoded tlog.
    reference : Source
        (system id, component id) of the reference clock.
    method : str, optional
        'timesync' (SYSTEM_TIME), 'xcorr' (a channel both streams carry), 'auto' (default:
        time sync where both streams have it, else cross-correlation), 'none'.
    max_offset : float, optional
        Largest clock offset searched by cross-correlation, s. Default 10.

    Returns
    -------
    dict of Source to ClockMap
        The map of each source.

    Raises
    ------
    ValueError
        For an unknown method, or a source that cannot be aligned.
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


SEGMENTS = ("all", "longest")


def convert_tlog(
    path: str | Path, *, servo_map: ServoMap | None = None, align: str = "auto",
    reference: str | None = None, rate: float | None = None, aircraft: str = "",
    max_offset: float = 10.0, max_gap: int = MAX_GAP_SAMPLES, segment: str = "all",
) -> FlightRecord:
    """A tlog as a FlightRecord: canonical SI channels, clocks aligned, uniform time base.

    Each channel comes from the source and message that carried it most often. A record is
    never interpolated across more than ``max_gap`` missing samples of a channel (its own
    sample interval; the record's ends count too): such a gap is refused with
    ``segment='all'``, and ``segment='longest'`` keeps the longest stretch without one. A tlog
    whose time stamps go back (two recordings in one file, a reset clock) is refused.

    Parameters
    ----------
    path : str or pathlib.Path
        The .tlog file.
    servo_map : ServoMap, optional
        Maps servo PWM to surface deflections.
    align : str, optional
        Clock alignment method (see :func:`align_sources`). Default 'auto'.
    reference : str, optional
        'sysid/compid' of the clock to use; default the source sending HIGHRES_IMU, else
        the busiest.
    rate : float, optional
        Output rate, Hz; default the fastest channel's.
    aircraft : str, optional
        Aircraft name (JSBSim model) for the record's metadata; its mass properties and
        reference geometry are added as a-priori values (MAVLink carries none).
    max_offset : float, optional
        Largest clock offset searched, s. Default 10.
    max_gap : int, optional
        Most missing samples interpolated across. Default ``MAX_GAP_SAMPLES``.
    segment : str, optional
        'all' (default) or 'longest'.

    Returns
    -------
    FlightRecord
        The flight, SI channels on a uniform time base.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    ValueError
        For a bad file, option or a gap/time reversal that is refused.
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
    fs = rate or grid_rate([t for _, t in chosen.values()], [intervals[c] for c in chosen])
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
            "losses": loss_dict(data.losses),
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
        provenance=f"MAVLink tlog {path} converted by flightid.sim.bridge.ground.tlog", extra=extra,
    )
    if aircraft:
        # MAVLink carries no mass properties or geometry: take them from the aircraft
        # definition, as a flight-test engineer takes them from the weight-and-balance sheet
        model = load(aircraft)
        meta.reference = model.reference
        out.update({k: np.full(grid.size, v) for k, v in model.mass_properties().items()})
        extra["bridge"]["a_priori"] = f"mass properties and reference geometry of {aircraft!r}"
    return FlightRecord(grid, out, meta)
