"""The time base of a converted tlog: each channel's nominal sample interval, the output
rate, and the gaps too long to interpolate across.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def nominal_interval(t: np.ndarray) -> float:
    """The interval a series was sent at: its most frequent time step.

    Steps are rounded to 0.1 ms; the smallest of equally frequent ones wins. With independent
    losses a step of k intervals has probability (1 - p) p^(k-1), largest at k = 1 whatever
    the loss rate p.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.

    Returns
    -------
    float
        The interval, s; inf with no positive step.
    """
    steps = np.round(np.diff(t), 4)
    steps = steps[steps > 0]
    if not steps.size:
        return float("inf")
    values, counts = np.unique(steps, return_counts=True)
    return float(values[np.argmax(counts)])


def grid_rate(times: list[np.ndarray], intervals: list[float]) -> float:
    """Rate of the most densely sampled series, to 1 mHz.

    Parameters
    ----------
    times : list of numpy.ndarray
        Each series' times on the reference clock, s.
    intervals : list of float
        Their nominal intervals, s.

    Returns
    -------
    float
        Rate, Hz; 0 when no series has two samples and a finite interval.
    """
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
    """Gaps of more than ``max_gap`` missing samples, including the ends of the span.

    Parameters
    ----------
    chosen : dict of str to numpy.ndarray
        Each channel's sample times, s.
    intervals : dict of str to float
        Each channel's nominal interval, s.
    start, end : float
        The span, s.
    max_gap : int
        Most missing samples (of the channel's own interval) allowed.

    Returns
    -------
    list of Gap
        The gaps; a channel with fewer than two samples is one gap over the span
        (``missing`` -1).
    """
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
    """The longest part of [start, end] that no gap overlaps.

    Parameters
    ----------
    start, end : float
        The span, s.
    gaps : list of Gap
        The gaps.

    Returns
    -------
    tuple of float
        (start, end) of the stretch, s.
    """
    best, lo = (start, start), start
    for g in sorted(gaps, key=lambda g: g.start):
        if g.start > lo and g.start - lo > best[1] - best[0]:
            best = (lo, g.start)
        lo = max(lo, g.end)
    if end - lo > best[1] - best[0]:
        best = (lo, end)
    return best
