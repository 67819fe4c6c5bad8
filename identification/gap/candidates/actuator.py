"""Actuator entries of the catalogue as candidates of the linear model, on records whose
surface channels hold the commands (``model.surfaces.surfaces_of``: the record's
``meta.extra["surfaces"]``, "command" or "position", default "position"; docs/record.md).

- ``actuator_lag`` (tau, s; option ``surface``): a first-order lag between the recorded
  command and the surface, one input state per surface (``model.lagged_input``);
  linear, so it is screened here.
- ``rate_limit``, ``deadband``, ``backlash``: nonlinear. They are not in the linear
  screening (a describing function would make their gain depend on the amplitude of each
  maneuver): ``identifiable.not_identifiable`` lists them, and they are scored with the
  JSBSim aircraft itself (``identification.effect_fit.fit_effect``) on a record of
  commands.
- ``actuator_bias``: a constant surface offset, which the state biases of the linear model
  absorb (``identifiable``).

On a record of surface positions the actuator has already acted on what was recorded:
no actuator entry is a candidate there. On a record of commands the diagnosis first
passes the commands through the aircraft's own actuators, read from its XML
(``model.surfaces.actuated``: each ``<actuator>``'s lag and rate limit, run as JSBSim runs
them, the commands held between updates), so the plain aircraft flown on its own commands
is at the null level and an ``actuator_lag`` candidate is the lag the model lacks.
"""

from __future__ import annotations

from collections.abc import Mapping

from flightid.identification.gap.model.edits import Candidate, extended, lagged_input
from flightid.identification.models.linear import LinearModel

TAU_START = 0.02  # s: start of the lag fit


def actuator_lag(surface: str) -> Candidate:
    """The catalogue's ``actuator_lag`` (tau, s) between the recorded command of
    ``surface`` and the surface.

    Parameters
    ----------
    surface : str
        "da", "dr" or "de", an input of the model.

    Returns
    -------
    Candidate
        Its catalogue entry, options and the linear-model parameters it frees (tau, s).
    """
    name = f"actuator_lag_{surface}"

    def wrap(model: LinearModel) -> LinearModel:
        column = model.inputs.index(surface)

        def build(v: Mapping[str, complex]) -> tuple:
            return lagged_input(model.build(v), column, v[name])

        return extended(model, {name: TAU_START}, build, (name,), surface)

    return Candidate("actuator_lag", {"surface": surface}, (name,), wrap, catalogue=("tau",))


def actuator_candidates(model: LinearModel, surfaces: str) -> list[Candidate]:
    """The actuator candidates for ``model``: a lag per surface input when ``surfaces``
    is "command", none for "position".

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.
    surfaces : str
        "position" or "command".

    Returns
    -------
    list of Candidate
        One ``actuator_lag`` per surface input on commands; [] on positions.
    """
    if surfaces != "command":
        return []
    return [actuator_lag(s) for s in model.inputs if s in ("da", "dr", "de")]
