"""The corrected model: the aircraft with the fitted airframe effects written into its
JSBSim XML (``flightid.sim.augment``), which flies in plain JSBSim; and that model flown
again with a record's measured inputs (``refly``): the gap of the full nonlinear JSBSim
model, not only of its linearisation."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from flightid.identification.effect_fit import CACHE
from flightid.identification.gap.jsbsim.symmetry import even_terms
from flightid.identification.gap.model.linearise import AXIS_OUTPUTS, start_condition
from flightid.record import FlightRecord
from flightid.sim.augment import augment, augment_cached
from flightid.sim.effects.airframe import (
    AugmentEffect,
    CgOffset,
    ControlEffectiveness,
    DerivativeDelta,
    InertiaScale,
    MassScale,
    TailIce,
    ThrustMoment,
)
from flightid.sim.flight.simulation import fly
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim

OUTPUTS = AXIS_OUTPUTS  # the channels compared, by the axis diagnosed
INPUTS = ("da", "dr", "de")  # the record's surfaces flown (increments on their first value)
# the mass-property candidates' effects and their parameters' neutral values
MASS_PROPERTIES = {"cg_offset": (CgOffset, {"x": 0.0, "z": 0.0}),
                   "mass_scale": (MassScale, {"factor": 1.0}),
                   "inertia_scale": (InertiaScale, {"ixx": 1.0, "iyy": 1.0, "izz": 1.0}),
                   "thrust_moment": (ThrustMoment, {"arm": 0.0})}


def airframe_effects(effects: list[Any]) -> list[AugmentEffect]:
    """The airframe effects among ranked effects (a ``Ranked`` or a pair of them).

    Parameters
    ----------
    effects : list of Ranked
        Ranked effects (a pair's parts included).

    Returns
    -------
    list of AugmentEffect
        The airframe ones as catalogue effects (catalogue units); sensor, mounting and
        actuator ones are left out.
    """
    out: list[AugmentEffect] = []
    for r in effects:
        cands = r.candidate.parts or (r.candidate,)
        for c in cands:
            prefix = f"{c.label}." if r.candidate.parts else ""
            p = {k[len(prefix):]: v["value"] for k, v in r.parameters.items()
                 if k.startswith(prefix)}
            if c.entry == "derivative_delta":
                out.append(DerivativeDelta(delta=p["delta"], derivative=c.options["derivative"],
                                           axes=c.options["axes"], source="flightid gap"))
            elif c.entry == "control_effectiveness":
                out.append(ControlEffectiveness(factor=p["factor"], surface=c.options["surface"],
                                                source="flightid gap"))
            elif c.entry == "tail_ice":
                out.append(TailIce(elevator=p["elevator"], stability=p["stability"],
                                   damping=p["damping"], source="flightid gap"))
            elif c.entry in MASS_PROPERTIES:  # the parameters not fitted at their neutral
                cls, neutral = MASS_PROPERTIES[c.entry]
                out.append(cls(**{**neutral, **p}, source="flightid gap"))
    return out


def write_aircraft(result: Any, folder: str | Path, name: str | None = None) -> Path:
    """Write ``result.aircraft`` with the airframe effects named on every diagnosed axis
    (the top one at its refined values when the diagnosis refined it) and with the model's
    even terms in sideslip, roll or yaw rate removed (``symmetry``: the aircraft flown
    again is then the model the diagnosis tested), under ``folder``; the new XML's path.
    Sensor effects are not written (they belong to the measurement, not the aircraft).

    Parameters
    ----------
    result : GapResult
        The diagnosis.
    folder : str or Path
        Where the aircraft folder is written.
    name : str or None
        The new aircraft's name (default: "<aircraft>-corrected").

    Returns
    -------
    Path
        The new XML. Raises ValueError when there is nothing to write.
    """
    named = result.named_all()
    effects = airframe_effects(named)
    refined = getattr(result, "refined", None)
    if refined is not None and effects:  # the top named effect as the refit has it
        effects[0] = refined.effect
    even = [e.straightening() for g in result.axes().values()
            for e in even_terms(g.linearised.kinks, g.linearised.axes)]
    if not effects and not even:
        if not named:
            raise ValueError("the diagnosis named no effect: nothing to write")
        raise ValueError(f"the named effect {named[0].candidate.label} is not an "
                         "airframe effect: nothing to write into the aircraft")
    stem = Path(str(result.aircraft)).stem
    return augment(result.aircraft, [*effects, *even], folder,
                   name=name or f"{stem}-corrected")


def gap_fractions(record: FlightRecord, flown: FlightRecord,
                  outputs: tuple[str, ...] = OUTPUTS["lateral"]) -> dict[str, float]:
    """Per channel: residual energy / measured energy, means removed from both (the trim
    offsets and sensor biases a re-flight from trim cannot know).

    Parameters
    ----------
    record : FlightRecord
        The record.
    flown : FlightRecord
        The model flown with its inputs.
    outputs : tuple of str
        The channels compared.

    Returns
    -------
    dict of str to float
    """
    out = {}
    n = min(len(record.time), len(flown.time))
    for ch in outputs:
        if ch not in record or ch not in flown:
            continue
        m = record[ch][:n] - np.mean(record[ch][:n])
        s = flown[ch][:n] - np.mean(flown[ch][:n])
        spread = float(np.sum(m * m))
        out[ch] = float(np.sum((m - s) ** 2)) / spread if spread > 0 else float("nan")
    return out


def fly_record(aircraft: str | Path, record: FlightRecord) -> FlightRecord:
    """``aircraft`` trimmed where ``record`` starts (``linearise.start_condition``, level)
    and flown open loop with the record's measured surfaces (rad, increments on their
    first sample) at the record's rate, driven past its actuators (the measured positions
    have passed the real ones). Raises DepartureError when it departs.

    Parameters
    ----------
    aircraft : str or Path
        JSBSim aircraft (name or XML path).
    record : FlightRecord
        The record whose surfaces (rad) are flown.

    Returns
    -------
    FlightRecord
        The flight, at the record's rate.
    """
    altitude, speed = start_condition(record)
    model = load(str(augment_cached(str(aircraft), [], CACHE, surface_drive=True)))
    trimmed = trim(model, max(altitude, 0.0), speed)
    t = record.time - record.time[0]
    rate = (len(t) - 1) / float(t[-1])
    controls = {s: record[s] - record[s][0] for s in INPUTS if s in record}
    return fly(model, trimmed, controls, duration_s=float(t[-1]), rate_hz=rate,
               surfaces="driven")
