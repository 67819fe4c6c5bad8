"""The corrected model: the aircraft with the fitted airframe effects written into its
JSBSim XML (``flightid.sim.augment``), which flies in plain JSBSim."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from flightid.sim.augment import augment
from flightid.sim.effects.airframe import AugmentEffect, ControlEffectiveness, DerivativeDelta


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
    return out


def write_aircraft(result: Any, folder: str | Path, name: str | None = None) -> Path:
    """Write ``result.aircraft`` with the airframe effects of ``result.named`` (the named
    effect or pair) under ``folder``; the new XML's path. Sensor effects are not
    written (they belong to the measurement, not the aircraft)."""
    if not result.named:
        raise ValueError("the diagnosis named no effect: nothing to write")
    effects = airframe_effects(result.named)
    if not effects:
        raise ValueError(f"the named effect {result.named[0].candidate.label} is not an "
                         "airframe effect: nothing to write into the aircraft")
    stem = Path(str(result.aircraft)).stem
    return augment(result.aircraft, effects, folder, name=name or f"{stem}-corrected")
