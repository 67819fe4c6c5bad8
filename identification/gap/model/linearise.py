"""The model under test, linearised at a record's condition, on the axis the records excite.

The JSBSim aircraft is trimmed at the records' mean true airspeed and altitude (level
flight), its truth derivatives (``flightid.sim.truth.derivatives``) are taken there, and
they become the fixed values of a perturbation model of ``identification.linear_models``
with the model's own mass, inertia and reference geometry and the trim's alpha and theta.
A derivative with a kink at trim (a drag polar whose linear segment ends there, as the
Navion's CD at 46 m/s) takes the mean of its two one-sided slopes.

- ``lateral``: the lateral model of Morelli & Klein (2016) example 6.1, body axes, all 15
  derivatives, aerodynamic + propulsive (outputs beta, p, r, phi, ay);
- ``longitudinal``: the full longitudinal model (Morelli & Klein 2016 ch. 3 and 6; Etkin &
  Reid 1996 ch. 4), stability axes (CL, CD; Cm is the same in both), all 11 derivatives
  (outputs V, alpha, q, theta, az). When the records carry the engine thrust (N, body x;
  the NASA record and the simulated ones do), it is a second input (``thrust_input``),
  the trim thrust is the records' mean, and the derivatives are the aerodynamic ones;
  otherwise the total (aerodynamic + propulsive) ones with no thrust term. Without the
  measured thrust the phugoid's speed damping (thrust falling with speed) is missing:
  Twin Otter null case V gap 0.019 without, 0.002 with.

The biases of the model (trim offsets) and its initial state are nuisance parameters
fitted on every window; the derivatives are the model.

Records with fewer channels (a hobby suite without attitudes, a record without vanes) are
diagnosed on the outputs they carry (``carried_outputs``): the model keeps every state
(phi still drives beta through gravity) and drops the output rows, and the output bias of
a dropped accelerometer. At least two outputs are needed. Records of surface commands
(``meta.extra["surfaces"] = "command"``, docs/record.md) reach the model through the
aircraft's own actuators (``model.surfaces.actuated``, in ``diagnose``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flightid.identification.data.axes import AXIS_NAMES
from flightid.identification.gap.model.surfaces import surfaces_of
from flightid.identification.models.linear import (
    LATERAL_BIASES,
    LATERAL_DERIVATIVES,
    LinearModel,
    ReferenceCondition,
    lateral,
)
from flightid.identification.models.longitudinal import (
    LONGITUDINAL_BIASES,
    LONGITUDINAL_DERIVATIVES,
    longitudinal,
)
from flightid.record import FlightRecord
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import Trim, trim
from flightid.sim.jsbsim.truth import Kink, derivatives

AXES = "body"  # the lateral model's derivative axes
PROPULSION = True  # total derivatives: what a flight (and a flight test) sees
NUISANCE = LATERAL_BIASES
DERIVATIVES = LATERAL_DERIVATIVES  # the lateral model's (kept: other modules import it)
# per axis: the derivatives of the model, their axes, the surfaces that excite it
AXIS_DERIVATIVES = {"lateral": LATERAL_DERIVATIVES, "longitudinal": LONGITUDINAL_DERIVATIVES}
AXIS_FRAME = {"lateral": "body", "longitudinal": "stability"}
TRIM_TERMS = ("CL_0", "CD_0")  # set by the trim, not candidates of a delta


@dataclass
class Linearised:
    """The aircraft's perturbation model of one axis at the record's condition."""

    aircraft: str  # as given (project name, stock JSBSim name or XML path)
    model: LinearModel  # all derivatives of the axis, start = the aircraft's truth
    derivatives: dict[str, float]  # the aircraft's derivatives (axes ``axes``, per rad)
    trim: Trim
    axes: str = AXES
    axis: str = "lateral"
    surfaces: str = "position"  # what the records' surface channels hold (or "command")
    # the axis's derivatives whose one-sided slopes differ at the trim (``truth.Kink``):
    # the model uses their mean
    kinks: dict[str, Kink] = field(default_factory=dict)


def nuisance(model: LinearModel) -> tuple[str, ...]:
    """The bias parameters of ``model`` (trim offsets, fitted on every window).

    Parameters
    ----------
    model : LinearModel

    Returns
    -------
    tuple of str
        The parameters named ``bias_*``.
    """
    return tuple(p for p in model.parameters if p.startswith("bias_"))


def record_condition(record: FlightRecord) -> tuple[float, float]:
    """(altitude m, true airspeed m/s): the record's means.

    Parameters
    ----------
    record : FlightRecord
        A record with V and h as channels or in ``meta.condition``.

    Returns
    -------
    tuple of float
        (altitude m, true airspeed m/s). Raises ValueError naming what is missing.
    """
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


def start_condition(record: FlightRecord) -> tuple[float, float]:
    """(altitude m, true airspeed m/s) to trim a JSBSim model at before flying it with the
    record's inputs: the metadata's condition where the record has one (a card's trim: an
    elevator 3211 drifts the mean airspeed away from it), else ``record_condition``.

    Parameters
    ----------
    record : FlightRecord
        A record.

    Returns
    -------
    tuple of float
        (altitude m, true airspeed m/s).
    """
    cond = record.meta.condition or {}
    if "altitude_m" in cond and "speed_m_s" in cond:
        return float(cond["altitude_m"]), float(cond["speed_m_s"])
    return record_condition(record)


AXIS_OUTPUTS = {"lateral": ("beta", "p", "r", "phi", "ay"),
                "longitudinal": ("V", "alpha", "q", "theta", "az")}
OUTPUT_BIASES = {"ay": "bias_ay", "az": "bias_az"}  # output biases of the models
MIN_OUTPUTS = 2


def carried_outputs(records: Sequence[FlightRecord], axis: str) -> tuple[str, ...]:
    """The outputs of ``axis``'s model that every record carries (in the model's order);
    raises naming the missing ones when fewer than ``MIN_OUTPUTS`` are left.

    Parameters
    ----------
    records : sequence of FlightRecord
        The records.
    axis : str
        "lateral" or "longitudinal".

    Returns
    -------
    tuple of str
        The outputs every record carries, in the model's order.
    """
    outs = tuple(c for c in AXIS_OUTPUTS[axis] if all(c in r for r in records))
    if len(outs) < MIN_OUTPUTS:
        missing = [c for c in AXIS_OUTPUTS[axis] if c not in outs]
        raise ValueError(f"gap: the records carry {len(outs)} of the {axis} outputs "
                         f"({', '.join(outs) or 'none'}; missing {', '.join(missing)}); "
                         f"at least {MIN_OUTPUTS} are needed")
    return outs


def restricted(model: LinearModel, outputs: Sequence[str]) -> LinearModel:
    """``model`` with only the output rows ``outputs`` (every state kept).

    Parameters
    ----------
    model : LinearModel
        The model.
    outputs : sequence of str
        The outputs kept, in order.

    Returns
    -------
    LinearModel
    """
    if tuple(outputs) == model.outputs:
        return model
    rows = [model.outputs.index(c) for c in outputs]

    def build(v: Mapping[str, complex]) -> tuple:
        A, B, C, D = model.build(v)
        return A, B, C[rows], D[rows]

    return LinearModel(model.name, model.states, model.inputs, tuple(outputs),
                       model.parameters, dict(model.start), build, model.condition,
                       model.description, dict(model.state_channels))


def linearise(aircraft: str, records: list[FlightRecord], axis: str = "lateral",
              surfaces: str | None = None) -> Linearised:
    """The ``aircraft`` trimmed at the records' mean airspeed and altitude, linearised on
    ``axis`` ("lateral" or "longitudinal"), with the outputs the records carry
    (``carried_outputs``). ``surfaces``: what the records' surface channels hold
    ("position" or "command"; None: their metadata, ``surfaces.surfaces_of``).

    Parameters
    ----------
    aircraft : str
        JSBSim aircraft: a project name, a stock JSBSim name or an XML path.
    records : list of FlightRecord
        The records of one condition.
    axis : str
        "lateral" or "longitudinal".
    surfaces : str or None
        "position" or "command" (None: the records' metadata).

    Returns
    -------
    Linearised
        The perturbation model of the axis (its derivatives per rad or per unit
        nondimensional rate, in the axis's axes), the trim, and the kinks at trim.
    """
    if axis not in AXIS_NAMES:
        raise ValueError(f"gap: axis must be one of {', '.join(AXIS_NAMES)}, got {axis!r}")
    conds = np.array([record_condition(r) for r in records])
    altitude, speed = (float(x) for x in conds.mean(axis=0))
    altitude = max(altitude, 0.0)  # a record at sea level averages a little below it
    model = load(aircraft)
    trimmed = trim(model, altitude, speed)
    frame = AXIS_FRAME[axis]
    thrust_input = axis == "longitudinal" and all("thrust" in r for r in records)
    truth = derivatives(model, trimmed, axes=frame, propulsion=PROPULSION and not thrust_input)
    s = truth.state
    thrust = float(np.mean([np.mean(r["thrust"]) for r in records])) if thrust_input else 0.0
    ref = model.reference
    condition = ReferenceCondition(
        V=s["V"], qbar=s["qbar"], alpha=trimmed.alpha, theta=trimmed.theta, mass=s["mass"],
        Ixx=s["Ixx"], Iyy=s["Iyy"], Izz=s["Izz"], Ixz=s["Ixz"], area=ref.area,
        span=ref.span, chord=ref.chord, thrust=thrust)
    names = AXIS_DERIVATIVES[axis]
    known = {**{k: 0.5 * (f.minus + f.plus) for k, f in truth.flags.items()}, **truth.values}
    outputs = carried_outputs(records, axis)
    dropped = {OUTPUT_BIASES[c] for c in AXIS_OUTPUTS[axis]
               if c not in outputs and c in OUTPUT_BIASES}
    if axis == "lateral":
        values = {d: float(known.get(d, 0.0)) for d in names}
        biases = tuple(b for b in LATERAL_BIASES if b not in dropped)
        linear = lateral(condition, names, start=values, biases=biases)
    else:
        values = {d: float(known.get(d, 0.0)) for d in names
                  if d not in TRIM_TERMS or not thrust_input}
        biases = tuple(b for b in LONGITUDINAL_BIASES if b not in dropped)
        linear = longitudinal(condition, names, start=values, thrust_input=thrust_input,
                              biases=biases)
        values = {d: float(linear.start[d]) for d in names}
    kind = surfaces_of(records, surfaces)
    linear = restricted(linear, outputs)
    kinks = {d: k for d, k in truth.flags.items() if d in names}
    return Linearised(aircraft, linear, values, trimmed, frame, axis, kind, kinks)
