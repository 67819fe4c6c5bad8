"""The named effect refined with the JSBSim aircraft itself as the model.

The ranking fits every candidate to the aircraft's *linearised* model at the record's mean
condition, which is fast and ranks well, but leaves the named effect's values a few per
cent short when the effect moves the trim (the iced Twin Otter trims 0.6 deg further
trailing edge up; its elevator 3211 drifts the airspeed): the perturbations are taken
about a slightly different point. ``refine`` fits the named airframe effect again by
output error with the augmented JSBSim aircraft flown from the record
(``identification.effect_fit``, Jategaonkar 2015, ch. 4), starting at the ranking's values:

- the surfaces are *driven* with the record's measured positions past the model's FCS
  (``sim.augment`` with ``surface_drive=True``): they have passed the real actuator and
  must not be lagged again;
- each driven surface's constant offset from the model's trim is fitted with the effect
  (a record's trim surface is known only to its noise and quantization, and 0.005 deg
  drifts the speed of a 30 s record);
- the outputs compared are the axis's states (the surfaces are inputs now; the specific
  forces add little and cost flights' worth of time);
- the bounds are corrected for colored residuals (Morelli & Klein 2016, eq. 6.54, with the
  fit's leverage put back: ``engine.bounds``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from flightid.identification.effect_fit import OFFSET, fit_effect
from flightid.identification.gap.jsbsim.write import OUTPUTS, airframe_effects
from flightid.identification.gap.model.linearise import AXIS_INPUTS, start_condition
from flightid.record import FlightRecord
from flightid.sim.effects.airframe import AugmentEffect
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.trim import TrimError

# the re-fly's channels without the specific forces (they add little and cost flights)
FITTED = {axis: tuple(c for c in chans if c not in ("ay", "az")) for axis, chans in OUTPUTS.items()}
FLIGHT_RATE_HZ = 100.0  # the refit's flights (the record's inputs interpolated to it)


@dataclass
class Refined:
    """The named effect refitted with JSBSim: values and bounds in catalogue units."""

    effect: AugmentEffect
    parameters: dict[str, dict[str, float]]  # name -> value, std (colored-corrected)
    linear: dict[str, dict[str, float]]  # the ranking's values, for comparison
    offsets: dict[str, float]  # fitted surface offsets from the model's trim (rad)
    cost_change: float  # ML cost of the refit minus the effect at its neutral values
    flights: int  # JSBSim flights the refit took
    record: int  # the index of the record refitted

    def to_json(self) -> dict[str, Any]:
        return {"name": self.effect.name, "parameters": self.parameters,
                "linear": self.linear, "offsets": self.offsets,
                "cost_change": self.cost_change, "flights": self.flights,
                "record": self.record}


def refinable(result: Any) -> AugmentEffect | None:
    """The airframe effect of the diagnosis's top named entry, or None (nothing named, a
    pair, or a sensor or mounting effect, which JSBSim's aircraft does not carry)."""
    if not result.named or result.named[0].candidate.parts:
        return None
    effects = airframe_effects(result.named[:1])
    return effects[0] if effects else None


class NotRefined(ValueError):
    """The named effect could not be refitted with JSBSim; the message says why."""


def refine(result: Any, records: list[FlightRecord], *,
           max_iterations: int = 12) -> Refined:
    """Refit the top named airframe effect of ``result`` (a ``GapResult``) on the longest
    of ``records`` with the augmented JSBSim aircraft. Raises NotRefined when there is
    none to refit (``refinable``), the aircraft with the effect does not trim where the
    record starts, or it departs when flown with the record's surfaces (open loop over the
    whole record: a model that is still wrong elsewhere may not stay in the air)."""
    effect = refinable(result)
    if effect is None or not records:
        raise NotRefined("the named entry is not one airframe effect (nothing named, a "
                         "pair, or a sensor effect)")
    k = max(range(len(records)), key=lambda i: records[i].time.size)
    record = records[k]
    surfaces = [c for c in AXIS_INPUTS[result.axis] if c in record]
    controls = {c: record[c] - record[c][0] for c in surfaces}
    outputs = [c for c in FITTED[result.axis] if c in record]
    named = result.named[0]
    linear = {n: dict(v) for n, v in named.parameters.items()}
    try:
        fit = fit_effect(record, result.aircraft, effect, controls=controls, outputs=outputs,
                         start={n: v["value"] for n, v in linear.items()},
                         max_iterations=max_iterations, colored=True, surfaces="driven",
                         flight_rate_hz=FLIGHT_RATE_HZ, offsets=surfaces,
                         condition=start_condition(record))
    except DepartureError as exc:
        raise NotRefined(f"{result.aircraft} with {effect.label()} departed when flown "
                         f"with the record's surfaces ({exc}); the ranking's values "
                         "stand") from exc
    except TrimError as exc:
        raise NotRefined(f"{result.aircraft} with {effect.label()} does not trim where "
                         f"the record starts ({exc}); the ranking's values stand") from exc
    params = {n: {"value": fit.values[n], "std": fit.std[n]} for n in fit.names}
    offsets = {n.removeprefix(OFFSET): v for n, v in fit.values.items() if n.startswith(OFFSET)}
    return Refined(fit.effect, params, linear, offsets, fit.cost - fit.neutral_cost,
                   fit.flights, k)
