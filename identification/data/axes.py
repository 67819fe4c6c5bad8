"""Which axes a record excites: the one rule behind ``identify``'s default model and the gap
diagnosis's axis choice.

A record that lists its maneuvers (a simulated one, ``meta.extra["maneuvers"]``) excites the
axes of the surfaces it maneuvers. Any other record excites the axes of the surfaces whose
spread (standard deviation) reaches ``EXCITED`` of the largest surface spread, so that a
pilot's small corrections or the sensor noise on the other surfaces do not count.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flightid.channels import LATERAL_INPUTS, LONGITUDINAL_INPUTS
from flightid.identification.data.windows import maneuvers
from flightid.record import FlightRecord

AXIS_NAMES = ("lateral", "longitudinal")
AXIS_INPUTS = {"lateral": LATERAL_INPUTS, "longitudinal": LONGITUDINAL_INPUTS}
# a surface is excited when its spread reaches this fraction of the largest surface spread
EXCITED = 0.25


def excited_surfaces(record: FlightRecord) -> set[str]:
    """The surfaces a record maneuvers.

    Parameters
    ----------
    record : FlightRecord
        A flight record; its surfaces ``de``, ``da``, ``dr`` in rad.

    Returns
    -------
    set of str
        The listed maneuvers' surfaces when the record lists them, else the surfaces
        whose standard deviation is at least ``EXCITED`` times the largest one (none
        when no surface moves).
    """
    listed = maneuvers(record)
    if listed:
        return {s for m in listed for s in m["surfaces"]}
    spread = {s: float(np.std(record[s])) for s in (*LONGITUDINAL_INPUTS, *LATERAL_INPUTS)
              if s in record}
    top = max(spread.values(), default=0.0)
    return {s for s, v in spread.items() if top > 0 and v >= EXCITED * top}


def excited_axes(records: Sequence[FlightRecord]) -> list[str]:
    """The axes the records excite (``excited_surfaces`` of each record), lateral first.

    Parameters
    ----------
    records : sequence of FlightRecord
        The flight records.

    Returns
    -------
    list of str
        ``"lateral"`` and/or ``"longitudinal"``: the axes with an excited surface
        (``AXIS_INPUTS``) in any of the records.
    """
    found: set[str] = set()
    for record in records:
        surfaces = excited_surfaces(record)
        found |= {a for a, inputs in AXIS_INPUTS.items() if set(inputs) & surfaces}
    return [a for a in AXIS_NAMES if a in found]
