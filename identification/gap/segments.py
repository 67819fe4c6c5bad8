"""The windows of the records a diagnosis fits and holds out: one per maneuver of the axis.

A simulated record lists its maneuvers (``identification.windows``): each maneuver on the
model's inputs (aileron and rudder: lateral; elevator: longitudinal) is one window, from
1 s before its first input to 8 s after its last or the next maneuver; a record whose
list has none on those inputs gives no window. A record that lists none (a real record)
is cut in two halves, so that one half can be held out of the fit of the other.
"""

from __future__ import annotations

from dataclasses import dataclass

from flightid.channels import LATERAL_INPUTS
from flightid.identification.data import windows
from flightid.record import FlightRecord

INPUTS = LATERAL_INPUTS
MIN_WINDOW_S = 4.0


@dataclass
class Segment:
    """One window of one record."""

    label: str
    record: FlightRecord
    start: float
    end: float


def segments(records: list[FlightRecord], names: list[str] | None = None,
             inputs: tuple[str, ...] = INPUTS) -> list[Segment]:
    """The maneuver windows of ``records`` (labelled by ``names`` or the record index).

    Parameters
    ----------
    records : list of FlightRecord
        The records.
    names : list of str or None
        Their labels (default: "record k").
    inputs : tuple of str
        The axis's surfaces ("da", "dr" lateral; "de" longitudinal).

    Returns
    -------
    list of Segment
        One per maneuver on ``inputs`` (1 s before it to 8 s after it, or the next
        maneuver), or the two halves of a record without a maneuver list.
    """
    out: list[Segment] = []
    for k, record in enumerate(records):
        name = names[k] if names else f"record {k + 1}"
        if windows.maneuvers(record):
            spans = _maneuver_spans(record, inputs)
        else:
            spans = _halves(record)
        for a, b in spans:
            out.append(Segment(f"{name} {a:.0f}-{b:.0f} s", record.slice(a, b), a, b))
    return out


def _maneuver_spans(record: FlightRecord, inputs: tuple[str, ...]) -> list[tuple[float, float]]:
    items = windows.maneuvers(record)
    t0, t_end = float(record.time[0]), float(record.time[-1])
    spans = []
    for m in items:
        if not set(m["surfaces"]) & set(inputs):
            continue
        start, end = float(m["start"]), float(m["end"])
        later = [float(o["start"]) for o in items if float(o["start"]) > end]
        a = max(t0, start - windows.LEAD_S)
        b = min([t_end, end + windows.SETTLE_S, *later])
        if b - a >= MIN_WINDOW_S:
            spans.append((a, b))
    return spans


def _halves(record: FlightRecord) -> list[tuple[float, float]]:
    t0, t_end = float(record.time[0]), float(record.time[-1])
    if t_end - t0 < 2 * MIN_WINDOW_S:
        return [(t0, t_end)]
    mid = 0.5 * (t0 + t_end)
    return [(t0, mid), (mid, t_end)]


def split(segment: Segment) -> list[Segment]:
    """One window cut in two halves in time (labelled "first half" and "second half"),
    so that one can be held out of the other's fit when an axis flies a single maneuver;
    the window itself when a half would be shorter than ``MIN_WINDOW_S``.

    Parameters
    ----------
    segment : Segment
        One window.

    Returns
    -------
    list of Segment
        Its two halves, or the window itself.
    """
    mid = 0.5 * (segment.start + segment.end)
    if mid - segment.start < MIN_WINDOW_S:
        return [segment]
    return [Segment(f"{segment.label} ({half} half)", segment.record.slice(a, b), a, b)
            for half, (a, b) in (("first", (segment.start, mid)),
                                 ("second", (mid, segment.end)))]
