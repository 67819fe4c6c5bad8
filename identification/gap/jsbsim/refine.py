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
  fit's leverage put back: ``engine.bounds``);
- the aircraft flown is the one ``write_aircraft`` writes: the other named airframe
  effects held at the ranking's values, and the model's even terms in sideslip, roll or
  yaw rate removed (``symmetry``);
- on the lateral axis each maneuver window of the record (``segments``; the halves of a
  record without a maneuver list) is fitted on its own, trimmed at the window's mean
  airspeed and altitude (``linearise.record_condition``, the diagnosis's reference) and
  flown from the record's state at its start (sideslip, bank, roll and yaw rate:
  ``refly.start_state``, as the re-fly), with its own surface offsets; the effect's
  parameters are the windows' inverse-variance mean (as the ranking's). A window where
  the aircraft departs is left out, and said so. The longitudinal axis is flown over the
  whole record from its trim (the phugoid's state at a window's start is the flight's
  history, as in ``refly``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.effect_fit import OFFSET, fit_effect
from flightid.identification.gap.jsbsim.refly import start_state
from flightid.identification.gap.jsbsim.symmetry import even_terms
from flightid.identification.gap.jsbsim.write import OUTPUTS, airframe_effects
from flightid.identification.gap.model.linearise import record_condition, start_condition
from flightid.identification.gap.segments import segments
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
    offsets: dict[str, float]  # fitted surface offsets from the model's trim (rad; the
    # windows' mean)
    cost_change: float  # ML cost of the refit minus the effect at its neutral values
    flights: int  # JSBSim flights the refit took
    record: int  # the index of the record refitted
    windows: int = 1  # windows fitted (their inverse-variance mean)
    departed: list[str] = field(default_factory=list)  # windows left out: departed

    def to_json(self) -> dict[str, Any]:
        return {"name": self.effect.name, "parameters": self.parameters,
                "linear": self.linear, "offsets": self.offsets,
                "cost_change": self.cost_change, "flights": self.flights,
                "record": self.record, "windows": self.windows, "departed": self.departed}


def refinable(result: Any) -> AugmentEffect | None:
    """The airframe effect of the diagnosis's top named entry, or None (nothing named, a
    pair, or a sensor or mounting effect, which JSBSim's aircraft does not carry).

    Parameters
    ----------
    result : GapResult
        The diagnosis.

    Returns
    -------
    AugmentEffect or None
    """
    if not result.named or result.named[0].candidate.parts:
        return None
    effects = airframe_effects(result.named[:1])
    return effects[0] if effects else None


class NotRefined(ValueError):
    """The named effect could not be refitted with JSBSim; the message says why."""


def refine(result: Any, records: list[FlightRecord], *,
           max_iterations: int = 12) -> Refined:
    """Refit the top named airframe effect of a diagnosis with the JSBSim aircraft.

    Parameters
    ----------
    result : GapResult
        The diagnosis (one axis).
    records : list of FlightRecord
        Its records; the longest is flown (module docstring: the lateral axis window by
        window from each window's start state).
    max_iterations : int
        Gauss-Newton steps at most per window.

    Returns
    -------
    Refined
        The effect at the refitted values, their bounds (catalogue units), the
        ranking's values, the surface offsets, the flights and the windows fitted.
        Raises NotRefined when there is none to refit (``refinable``), the aircraft with
        the effect does not trim where the record starts, or it departs on every window.
    """
    effect = refinable(result)
    if effect is None or not records:
        raise NotRefined("the named entry is not one airframe effect (nothing named, a "
                         "pair, or a sensor effect)")
    k = max(range(len(records)), key=lambda i: records[i].time.size)
    record = records[k]
    surfaces = [c for c in AXIS_INPUTS[result.axis] if c in record]
    outputs = [c for c in FITTED[result.axis] if c in record]
    named = result.named[0]
    linear = {n: dict(v) for n, v in named.parameters.items()}
    base = held(result)
    if result.axis == "lateral":
        spans = [s.record for s in segments([record], None, AXIS_INPUTS[result.axis])]
    else:
        spans = [record]
    fits, departed = [], []
    for window in spans:
        initial = ((lambda tr, w=window: start_state(tr, record, w))
                   if result.axis == "lateral" else None)
        try:
            fits.append(fit_effect(
                window, result.aircraft, effect,
                controls={c: window[c] - record[c][0] for c in surfaces}, outputs=outputs,
                start={n: v["value"] for n, v in linear.items()},
                max_iterations=max_iterations, colored=True, surfaces="driven",
                flight_rate_hz=FLIGHT_RATE_HZ, offsets=surfaces,
                condition=_condition(window if result.axis == "lateral" else None, record),
                initial=initial, base=base))
        except DepartureError as exc:
            departed.append(f"{window.time[0]:.0f}-{window.time[-1]:.0f} s ({exc})")
        except TrimError as exc:
            raise NotRefined(f"{result.aircraft} with {effect.label()} does not trim where "
                             f"the record starts ({exc}); the ranking's values stand") from exc
    if not fits:
        raise NotRefined(f"{result.aircraft} with {effect.label()} departed on every window "
                         f"flown with the record's surfaces: {'; '.join(departed)}; the "
                         "ranking's values stand")
    params = _mean(fits)
    # each window's own offsets (its trim surface), their mean over the windows reported
    offsets = {c: float(np.mean([f.values[OFFSET + c] for f in fits])) for c in surfaces}
    refit = dataclasses.replace(effect, **{n: v["value"] for n, v in params.items()})
    return Refined(refit, params, linear, offsets,
                   sum(f.cost - f.neutral_cost for f in fits), sum(f.flights for f in fits),
                   k, windows=len(fits), departed=departed)


def _condition(window: FlightRecord | None, record: FlightRecord) -> tuple[float, float]:
    """(altitude m, airspeed m/s) to trim at: the window's means (a record at sea level
    averages a little below it: held at 0), or where the record starts."""
    if window is None:
        return start_condition(record)
    altitude, speed = record_condition(window)
    return max(altitude, 0.0), speed


def held(result: Any) -> tuple[AugmentEffect, ...]:
    """What the refit holds in the aircraft beside the refitted effect.

    Parameters
    ----------
    result : GapResult
        The diagnosis (one axis).

    Returns
    -------
    tuple of AugmentEffect
        As ``write_aircraft`` writes them: the other named airframe effects of the axis
        and the model's even terms removed (``symmetry.even_terms``).
    """
    others = airframe_effects(result.named[1:])
    lin = result.linearised
    return (*others, *(e.straightening() for e in even_terms(lin.kinks, lin.axes)))


def _mean(fits: list[Any]) -> dict[str, dict[str, float]]:
    """The effect's parameters over the windows' fits: inverse-variance mean and bound."""
    out = {}
    for n in fits[0].names:
        pts = [(f.values[n], f.std[n]) for f in fits if math.isfinite(f.std[n]) and f.std[n] > 0]
        if not pts:
            out[n] = {"value": float(np.mean([f.values[n] for f in fits])), "std": math.inf}
            continue
        w = np.array([1.0 / s**2 for _, s in pts])
        v = float(np.sum(w * np.array([v for v, _ in pts])) / np.sum(w))
        out[n] = {"value": v, "std": float(1.0 / math.sqrt(np.sum(w)))}
    return out
