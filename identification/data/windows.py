"""Maneuver windows: the part of a record that belongs to the maneuvers on given inputs.

A simulated record lists its maneuvers in ``meta.extra['maneuvers']`` as
[{"kind", "surfaces", "start", "end"}] (s). A linear perturbation model of one axis fits
best on the window of that axis's maneuvers with its free response: output error on a
whole card would fit the other axes' maneuvers and long stretches of turbulence-driven
drift to a model that has no inputs for them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from flightid.record import FlightRecord

META_KEY = "maneuvers"
LEAD_S = 1.0  # s of trim kept before the first input of a window
SETTLE_S = 8.0  # s of free response kept after the last input of a window


def maneuvers(record: FlightRecord) -> list[dict[str, Any]]:
    """The record's maneuvers, empty when unknown.

    Parameters
    ----------
    record : FlightRecord
        The flight.

    Returns
    -------
    list of dict
        One {"kind", "surfaces", "start", "end"} per maneuver (times in s).
    """
    return list(record.meta.extra.get(META_KEY) or [])


def window(record: FlightRecord, inputs: Sequence[str]) -> tuple[float, float] | None:
    """(start, end) of the record's maneuvers on ``inputs`` plus lead and settling time.

    The window ends before the next maneuver on other inputs.

    Parameters
    ----------
    record : FlightRecord
        The flight.
    inputs : sequence of str
        The surfaces whose maneuvers are wanted.

    Returns
    -------
    tuple of float or None
        (start, end), s; None when the record lists no maneuver on them.
    """
    items = maneuvers(record)
    chosen = [m for m in items if set(m["surfaces"]) & set(inputs)]
    if not chosen:
        return None
    t0, t_end = float(record.time[0]), float(record.time[-1])
    first = min(float(m["start"]) for m in chosen)
    last = max(float(m["end"]) for m in chosen)
    later = [float(m["start"]) for m in items if float(m["start"]) > last]
    start = max(t0, first - LEAD_S)
    end = min([t_end, last + SETTLE_S, *later])
    return start, end


def select(record: FlightRecord, inputs: Sequence[str]) -> tuple[FlightRecord, tuple | None]:
    """The record cut to ``window(record, inputs)``, and the window.

    Parameters
    ----------
    record : FlightRecord
        The flight.
    inputs : sequence of str
        The surfaces whose maneuvers are wanted.

    Returns
    -------
    tuple of (FlightRecord, tuple or None)
        (the cut record, (start, end) s), or (record, None) when there is no window.
    """
    span = window(record, inputs)
    if span is None:
        return record, None
    return record.slice(*span), span
