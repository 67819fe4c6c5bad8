"""Actuator entries of the catalogue as candidates of the linear model, on records whose
surface channels hold the commands (``surfaces_of``: the record's ``meta.extra["surfaces"]``,
"command" or "position", default "position"; docs/record.md).

- ``actuator_lag`` (tau, s; option ``surface``): a first-order lag between the recorded
  command and the surface, one input state per surface (``effect_model.lagged_input``);
  linear, so it is screened here.
- ``rate_limit``, ``deadband``, ``backlash``: nonlinear. They are not in the linear
  screening (a describing function would make their gain depend on the amplitude of each
  maneuver): ``identifiable.not_identifiable`` lists them, and they are scored with the
  JSBSim aircraft itself (``identification.effect_fit.fit_effect``) on a record of
  commands.
- ``actuator_bias``: a constant surface offset, which the state biases of the linear model
  absorb (``identifiable``).

On a record of surface positions the actuator has already acted on what was recorded:
no actuator entry is a candidate there. On a record of commands the model includes the
aircraft's own actuator lags (``with_actuators``, read from its XML by
``sim.actuators.actuator_lags``), so an ``actuator_lag`` candidate is the lag the model
lacks; the aircraft's own rate limits are not in the linear model (a 4 deg step through
the Navion's 60 deg/s limit looks like 0.07 s more lag), so a command record of large,
fast steps on an aircraft with slow actuators names a lag that is the rate limit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from flightid.identification.gap.effect_model import Candidate, extended, lagged_input
from flightid.identification.models.linear import LinearModel
from flightid.record import FlightRecord

SURFACE_KINDS = ("position", "command")
SURFACES_KEY = "surfaces"  # the key of FlightRecord.meta.extra
TAU_START = 0.02  # s: start of the lag fit


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


def actuator_lag(surface: str) -> Candidate:
    """The catalogue's ``actuator_lag`` (tau, s) between the recorded command of
    ``surface`` and the surface."""
    name = f"actuator_lag_{surface}"

    def wrap(model: LinearModel) -> LinearModel:
        column = model.inputs.index(surface)

        def build(v: Mapping[str, complex]) -> tuple:
            return lagged_input(model.build(v), column, v[name])

        return extended(model, {name: TAU_START}, build, (name,))

    return Candidate("actuator_lag", {"surface": surface}, (name,), wrap, catalogue=("tau",))


def actuator_candidates(model: LinearModel, surfaces: str) -> list[Candidate]:
    """The actuator candidates for ``model``: a lag per surface input when ``surfaces``
    is "command", none for "position"."""
    if surfaces != "command":
        return []
    return [actuator_lag(s) for s in model.inputs if s in ("da", "dr", "de")]
