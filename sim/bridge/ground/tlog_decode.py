"""A tlog's packets decoded: :func:`decode_tlog` and what it returns.

Every packet becomes canonical channels (``bridge.decoding``) grouped by source and
message into :class:`Series` on the source's own clock, with the time-sync pairs, the
sequence losses, the time reversals and the read problems (:class:`TlogData`); messages
without a time field are timed from their neighbours (:func:`cadence_times`).
``ground.tlog`` aligns and resamples them into a FlightRecord.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flightid.sim.bridge.decoding import decode, message_time
from flightid.sim.bridge.frames import read_tlog
from flightid.sim.bridge.ground.sources import Source, SourceLoss, sequence_losses, source_name
from flightid.sim.bridge.messages import ServoMap


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
