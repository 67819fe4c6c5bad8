"""The corrected model: the aircraft with the fitted airframe effects written into its
JSBSim XML (``flightid.sim.augment``), which flies in plain JSBSim; and that model flown
again with a record's measured inputs (``refly``): the gap of the full nonlinear JSBSim
model, not only of its linearisation."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from flightid.identification.effect_fit import CACHE
from flightid.identification.gap.linearise import AXIS_OUTPUTS, start_condition
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
from flightid.sim.flight.simulation import DepartureError, fly
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
    """The airframe effects among ranked effects (a ``Ranked`` or a pair of them)."""
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
    """Write ``result.aircraft`` with the airframe effects of ``result.named`` (the named
    effect or pair; the top one at its refined values when the diagnosis refined it)
    under ``folder``; the new XML's path. Sensor effects are not
    written (they belong to the measurement, not the aircraft)."""
    if not result.named:
        raise ValueError("the diagnosis named no effect: nothing to write")
    effects = airframe_effects(result.named)
    if not effects:
        raise ValueError(f"the named effect {result.named[0].candidate.label} is not an "
                         "airframe effect: nothing to write into the aircraft")
    refined = getattr(result, "refined", None)
    if refined is not None:  # the top named effect (refine.refinable) as the refit has it
        effects[0] = refined.effect
    stem = Path(str(result.aircraft)).stem
    return augment(result.aircraft, effects, folder, name=name or f"{stem}-corrected")


def gap_fractions(record: FlightRecord, flown: FlightRecord,
                  outputs: tuple[str, ...] = OUTPUTS["lateral"]) -> dict[str, float]:
    """Per channel: residual energy / measured energy, means removed from both (the trim
    offsets and sensor biases a re-flight from trim cannot know)."""
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
    have passed the real ones). Raises DepartureError when it departs."""
    altitude, speed = start_condition(record)
    model = load(str(augment_cached(str(aircraft), [], CACHE, surface_drive=True)))
    trimmed = trim(model, max(altitude, 0.0), speed)
    t = record.time - record.time[0]
    rate = (len(t) - 1) / float(t[-1])
    controls = {s: record[s] - record[s][0] for s in INPUTS if s in record}
    return fly(model, trimmed, controls, duration_s=float(t[-1]), rate_hz=rate,
               surfaces="driven")


def refly(result: Any, records: FlightRecord | list[FlightRecord], folder: str | Path,
          written: str | Path | None = None) -> dict[str, Any]:
    """The JSBSim shrink: the aircraft as is and the corrected one (``written``, else
    written now under ``folder``) flown with each record's measured inputs from trim at the
    record's condition; per record and channel the gap (residual / measured energy, means
    removed) before and after, and the overall (mean over channels). Open loop from trim:
    a record that does not start in trim, or a slow mode (spiral, phugoid) the model gets
    a little wrong, leaves a gap no effect of the catalogue closes."""
    records = [records] if isinstance(records, FlightRecord) else list(records)
    outputs = OUTPUTS[getattr(result, "axis", "lateral")]
    path = Path(written) if written is not None else write_aircraft(result, folder)
    out: dict[str, Any] = {"aircraft": str(path), "records": []}
    for k, record in enumerate(records):
        row: dict[str, Any] = {"record": k + 1}
        for key, model in (("before", result.aircraft), ("after", path)):
            try:
                row[key] = gap_fractions(record, fly_record(model, record), outputs)
            except DepartureError as exc:
                row[key] = None
                row[f"{key}_departed"] = str(exc)
        if row["before"] and row["after"]:
            row["channels"] = {c: {"before": row["before"][c], "after": row["after"][c],
                                   "shrink": _shrink(row["before"][c], row["after"][c])}
                               for c in row["before"] if c in row["after"]}
            b, a = (float(np.nanmean(list(row[x].values()))) for x in ("before", "after"))
            row["overall"] = {"before": b, "after": a, "shrink": _shrink(b, a)}
        out["records"].append(row)
    done = [r["overall"] for r in out["records"] if "overall" in r]
    if done:
        b = float(np.mean([d["before"] for d in done]))
        a = float(np.mean([d["after"] for d in done]))
        out["overall"] = {"before": b, "after": a, "shrink": _shrink(b, a)}
    return out


def _shrink(before: float, after: float) -> float:
    return (before - after) / before if before > 0 else float("nan")
