"""What a simulated record carries about its own flight: maneuvers, truth, a priori values.

``flightid identify`` reads these from the record's metadata, so a simulated record is
windowed by its maneuvers and scored against its own truth without a separate file.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from flightid.scenarios.input_design import InputDesign
from flightid.sim.jsbsim.model import Model
from flightid.sim.jsbsim.trim import Trim
from flightid.sim.jsbsim.truth import derivatives


def maneuver_list(designs: Sequence[InputDesign]) -> list[dict[str, Any]]:
    """[{"kind", "surfaces", "start", "end"}] (s) of the flown input designs.

    Parameters
    ----------
    designs : Sequence[InputDesign]
        The flown input designs.

    Returns
    -------
    list[dict[str, Any]]
        One dict per design: "kind", "surfaces" (list of str), "start" and "end" (s).
    """
    return [{"kind": d.kind, "surfaces": list(d.surfaces()), "start": float(d.start),
             "end": float(d.end)} for d in designs]


def truth_table(model: Model, trimmed: Trim) -> dict[str, Any]:
    """The exact derivatives at the trim, {"trim", "body": {...}, "stability": {...},
    "kinks", "source"}: aerodynamic derivatives of the JSBSim model (per rad, rates
    nondimensional).

    Parameters
    ----------
    model : Model
        The JSBSim aircraft model.
    trimmed : Trim
        The trim at which the derivatives are taken.

    Returns
    -------
    dict[str, Any]
        "trim" (the trim condition), "body" and "stability" (derivative name -> value),
        "kinks" (sorted names flagged by the differencing) and "source" (str).
    """
    body = derivatives(model, trimmed, axes="body")
    stability = derivatives(model, trimmed, axes="stability")
    return {
        "trim": trimmed.condition,
        "body": dict(sorted(body.values.items())),
        "stability": dict(sorted(stability.values.items())),
        "kinks": sorted(set(body.flags) | set(stability.flags)),
        "source": f"JSBSim {model.name}: central differences of its aerodynamic coefficients "
                  f"at the trim ({trimmed.altitude_m:g} m, {trimmed.speed_m_s:g} m/s)",
    }
