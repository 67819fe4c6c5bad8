"""A .tlog as a FlightRecord: canonical channels in SI (``tlog_decode.decode_tlog``), separately
clocked recorders aligned to the reference recorder's clock (``align``), and every channel
resampled onto one uniform time base by linear interpolation (the method and its details
are stated in the metadata). Reading a tlog imports nothing of the air side.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flightid.record import FlightRecord, RecordMeta
from flightid.sim.bridge.decoding import CHANNEL_SOURCES
from flightid.sim.bridge.ground.align import ClockMap, timesync_map, xcorr_map
from flightid.sim.bridge.ground.gaps import (
    MAX_GAP_SAMPLES,
    MIN_RECORD_SAMPLES,
    grid_rate,
    long_gaps,
    longest_stretch,
    nominal_interval,
)
from flightid.sim.bridge.ground.sources import Source, loss_dict, source_name
from flightid.sim.bridge.ground.tlog_decode import Series, TlogData, decode_tlog
from flightid.sim.bridge.messages import ServoMap
from flightid.sim.jsbsim.model import load


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
