"""What a record's surface channels hold (``surfaces_of``: positions, or the commands ahead
of the actuators, ``meta.extra["surfaces"]``; docs/record.md), and the model with the
aircraft's own actuator lags on a record of commands (``with_actuators``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from flightid.identification.gap.model.edits import extended, lagged_input
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

SURFACE_KINDS = ("position", "command")
SURFACES_KEY = "surfaces"  # the key of FlightRecord.meta.extra


def surfaces_of(records: Sequence[FlightRecord], surfaces: str | None = None) -> str:
    """What the records' surface channels hold: ``surfaces`` when given, else their
    metadata (``meta.extra["surfaces"]``; "position" when absent). Raises naming the
    value when it is neither "position" nor "command", or when the records disagree."""
    if surfaces is not None:
        found = {surfaces}
    else:
        found = {str(r.meta.extra.get(SURFACES_KEY, "position")) for r in records}
        found = found or {"position"}
    bad = sorted(found - set(SURFACE_KINDS))
    if bad:
        raise ValueError(f"surfaces must be one of {', '.join(SURFACE_KINDS)} "
                         f"(meta.extra[{SURFACES_KEY!r}] or the option), got {bad[0]!r}")
    if len(found) > 1:
        raise ValueError("the records disagree on what their surface channels hold "
                         f"(meta.extra[{SURFACES_KEY!r}]: {', '.join(sorted(found))}); "
                         "give surfaces= for all of them")
    return found.pop()


def with_actuators(model: LinearModel, lags: Mapping[str, float]) -> LinearModel:
    """``model`` with each surface input lagged by its fixed time constant (s) in
    ``lags`` (the aircraft's own actuators, not fitted); surfaces without one unchanged."""
    for surface in model.inputs:
        tau = float(lags.get(surface, 0.0))
        if tau > 0:
            model = _fixed_lag(model, surface, tau)
    return model


def _fixed_lag(model: LinearModel, surface: str, tau: float) -> LinearModel:
    column = model.inputs.index(surface)

    def build(v: Mapping[str, complex]) -> tuple:
        return lagged_input(model.build(v), column, tau)

    return extended(model, {}, build, (f"actuator_{surface}",))
