"""The model under test, linearised at a record's condition.

First version: the JSBSim aircraft is trimmed at the record's mean true airspeed and
altitude (level flight), its truth derivatives (``flightid.sim.truth.derivatives``, body
axes, aerodynamic) are taken there, and they become the fixed values of the lateral
perturbation model of ``identification.linear_models`` (Morelli & Klein 2016 example 6.1)
with the model's own mass, inertia and reference geometry and the trim's alpha and theta.
The biases of that model (trim offsets) and its initial state are nuisance parameters
fitted on every window; the derivatives are the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flightid.identification.linear_models import (
    LATERAL_BIASES,
    LATERAL_DERIVATIVES,
    LinearModel,
    ReferenceCondition,
    lateral,
)
from flightid.record import FlightRecord
from flightid.sim.model import load
from flightid.sim.trim import Trim, trim
from flightid.sim.truth import derivatives

AXES = "body"
PROPULSION = True  # total derivatives: what a flight (and a flight test) sees
NUISANCE = LATERAL_BIASES
DERIVATIVES = LATERAL_DERIVATIVES


@dataclass
class Linearised:
    """The aircraft's lateral perturbation model at the record's condition."""

    aircraft: str  # as given (project name, stock JSBSim name or XML path)
    model: LinearModel  # lateral, all derivatives, start = the aircraft's truth
    derivatives: dict[str, float]  # the aircraft's lateral derivatives (body axes, per rad)
    trim: Trim
    axes: str = AXES


def record_condition(record: FlightRecord) -> tuple[float, float]:
    """(altitude m, true airspeed m/s): the record's means."""
    cond = record.meta.condition or {}
    if "V" in record:
        speed = float(np.mean(record["V"]))
    elif "V" in cond:
        speed = float(cond["V"])
    else:
        raise ValueError("the record has no airspeed V (channel or meta.condition)")
    for key in ("h", "altitude"):
        if key in record:
            return float(np.mean(record[key])), speed
    for key in ("h", "altitude_m", "altitude"):
        if key in cond:
            return float(cond[key]), speed
    raise ValueError("the record has no altitude h (channel or meta.condition)")


def linearise(aircraft: str, records: list[FlightRecord]) -> Linearised:
    """The ``aircraft`` trimmed at the records' mean airspeed and altitude, linearised."""
    conds = np.array([record_condition(r) for r in records])
    altitude, speed = (float(x) for x in conds.mean(axis=0))
    altitude = max(altitude, 0.0)  # a record at sea level averages a little below it
    model = load(aircraft)
    trimmed = trim(model, altitude, speed)
    truth = derivatives(model, trimmed, axes=AXES, propulsion=PROPULSION)
    s = truth.state
    ref = model.reference
    condition = ReferenceCondition(
        V=s["V"], qbar=s["qbar"], alpha=trimmed.alpha, theta=trimmed.theta, mass=s["mass"],
        Ixx=s["Ixx"], Iyy=s["Iyy"], Izz=s["Izz"], Ixz=s["Ixz"], area=ref.area,
        span=ref.span, chord=ref.chord)
    values = {d: float(truth.values.get(d, 0.0)) for d in DERIVATIVES}
    linear = lateral(condition, DERIVATIVES, start=values)
    return Linearised(aircraft, linear, values, trimmed)
