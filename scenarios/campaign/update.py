"""``--update-aircraft OUT/``: the model aircraft with its tables relocated to the flight
points, written as a JSBSim aircraft, and the gap on held-out test points before and after.

Per derivative, ``identification.envelope_fit.fit_correction`` relocates the model curve
to the campaign's estimates (the F-111C approach). Each kept correction becomes a catalogue
effect: a ``shift`` a ``derivative_delta``; a ``scale`` or ``shift+slope`` a
``derivative_table`` in the campaign's x (airspeed or alpha) between the outermost points
(the table holds its end values beyond them), a ``scale`` a ``derivative_delta`` when x
cannot carry a table. ``sim.augment.augment`` writes them into OUT/aircraft/<name>/.

The held-out points (``[[held_out]]``) are flown with the flown aircraft (the campaign's
effects included) and its sensors; the measured record, reduced as at the test points, is
flown again by the model, by the updated aircraft and by the flown aircraft itself (the
floor: what a perfect model leaves, sensor noise). Each is flown as the gap diagnosis's
re-fly flies a record (``identification.gap.jsbsim.refly.fly_window``): per maneuver window of
the axis, a lateral window from its own start state, a longitudinal one from the trim
through what precedes it, with the measured surfaces plus constant offsets refitted on the
window (the bias and initial conditions of a prediction case, Morelli & Klein 2016). The
gap is the diagnosis's: per channel, residual over measured energy, means removed
(``gap_fractions``), averaged over the axis's channels and windows. The whole record
flown open loop from the trim without offsets (``identification.gap.jsbsim.write.fly_record``)
is kept as ``open_loop`` (the slow modes drift over 28 s).
"""

from __future__ import annotations

import contextlib
import io
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from flightid.identification.data.axes import AXIS_INPUTS
from flightid.identification.effect_fit import CACHE
from flightid.identification.envelope_fit import Correction, fit_correction
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.identification.gap.jsbsim.refly import fly_window
from flightid.identification.gap.jsbsim.write import fly_record, gap_fractions
from flightid.identification.gap.model.linearise import AXIS_OUTPUTS, start_condition
from flightid.identification.gap.segments import segments
from flightid.record import FlightRecord
from flightid.scenarios.campaign.card import Campaign, point_card
from flightid.scenarios.campaign.curve import model_at
from flightid.scenarios.campaign.point import fly_held_out, model_values
from flightid.scenarios.cards import augmented, card_from_dict
from flightid.sim.augment import augment, augment_cached
from flightid.sim.effects.airframe import (
    DERIVATIVES,
    AugmentEffect,
    DerivativeDelta,
    DerivativeTable,
)
from flightid.sim.jsbsim.model import load, quiet
from flightid.sim.jsbsim.trim import TrimError, trim

SCHEDULES = {"speed": "airspeed", "alpha": "alpha"}
# the condition each estimate stands for (point.flown_condition), by the campaign's x
FLOWN = {"speed": "speed_flown", "alpha": "alpha_flown"}


def _x(campaign: Campaign, rows: pd.DataFrame) -> np.ndarray:
    """The x of each estimate: its flown condition where the campaign's x has one."""
    column = FLOWN.get(campaign.x, campaign.x)
    return rows[column if column in rows else campaign.x].to_numpy()


def flown_model(campaign: Campaign, df: pd.DataFrame) -> pd.DataFrame:
    """The estimated rows of ``df`` with ``model_flown``: the model's value on the
    campaign's path at each estimate's x (``_x``: its flown condition,
    ``point.flown_condition``), from the JSBSim tables (``curve.model_at``; one trim per
    point and distinct flown x). Where the estimate has no flown condition, or the model
    cannot be trimmed there, the model's value at the trim (``model``).

    Parameters
    ----------
    campaign : Campaign
        The campaign whose estimates ``df`` are.
    df : pandas.DataFrame
        The campaign's estimates (``estimates.parquet``).

    Returns
    -------
    pandas.DataFrame
        The rows with status 'estimated', with the column ``model_flown``.
    """
    est = df[df["status"] == STATUS_ESTIMATED].copy()
    x = _x(campaign, est)
    values = est["model"].to_numpy(dtype=float).copy()
    if campaign.x in FLOWN:
        cache: dict[tuple[int, float], dict[str, float]] = {}
        for k, (index, name) in enumerate(zip(est["index"], est["name"], strict=True)):
            if not np.isfinite(x[k]):
                continue
            key = (int(index), float(x[k]))
            if key not in cache:
                try:
                    cache[key] = model_at(campaign, campaign.points[key[0]], key[1])
                except TrimError:
                    cache[key] = {}
            values[k] = cache[key].get(str(name), values[k])
    est["model_flown"] = values
    return est


def corrections(campaign: Campaign, df: pd.DataFrame) -> list[Correction]:
    """Per estimated derivative, its model curve relocated to the flight points: each
    estimate against the model's value at its flown condition (``flown_model``).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    df : pandas.DataFrame
        The estimates table, optionally with the ``model_flown`` column.

    Returns
    -------
    list[Correction]
        One fitted correction per estimated derivative, sorted by name.
    """
    est = df if "model_flown" in df else flown_model(campaign, df)
    est = est[est["status"] == STATUS_ESTIMATED]
    out = []
    for name, rows in est.groupby("name", sort=True):
        trend = campaign.x in SCHEDULES and not (
            campaign.x == "alpha" and str(name).endswith(("_alpha", "_alphadot")))
        out.append(fit_correction(str(name), _x(campaign, rows),
                                  rows["estimate"].to_numpy(), rows["std"].to_numpy(),
                                  rows["model_flown"].to_numpy(), trend=trend))
    return out


def correction_effects(campaign: Campaign, df: pd.DataFrame, fitted: list[Correction]
                       ) -> list[AugmentEffect]:
    """The catalogue effects that write the kept corrections into the model aircraft.

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    df : pandas.DataFrame
        The estimates table, optionally with the ``model_flown`` column.
    fitted : list[Correction]
        The corrections from :func:`corrections`.

    Returns
    -------
    list[AugmentEffect]
        A derivative delta or a delta table scheduled on the campaign's x, per kept correction.
    """
    effects: list[AugmentEffect] = []
    est = df if "model_flown" in df else flown_model(campaign, df)
    est = est[est["status"] == STATUS_ESTIMATED]
    for c in fitted:
        if c.form == "none" or c.name not in DERIVATIVES:
            continue
        rows = est[est["name"] == c.name]
        order = np.argsort(_x(campaign, rows))
        x, m = _x(campaign, rows)[order], rows["model_flown"].to_numpy()[order]
        if c.form == "shift" or campaign.x not in SCHEDULES or np.ptp(x) == 0:
            delta = float(np.mean(c.delta(x, m)))
            effects.append(DerivativeDelta(delta=delta, derivative=c.name, axes="body"))
            continue
        effects.append(DerivativeTable(
            derivative=c.name, axes="body", schedule=SCHEDULES[campaign.x],
            low=float(x[0]), high=float(x[-1]), delta_low=float(c.delta(x[0], m[0])),
            delta_high=float(c.delta(x[-1], m[-1]))))
    return effects


def write_updated(campaign: Campaign, effects: list[AugmentEffect], folder: str | Path
                  ) -> Path:
    """OUT/aircraft/<aircraft>-updated/<aircraft>-updated.xml: the model aircraft with the
    corrections (plain JSBSim loads it from OUT).

    Parameters
    ----------
    campaign : Campaign
        The campaign (its aircraft).
    effects : list[AugmentEffect]
        The correction effects.
    folder : str or Path
        Output folder OUT.

    Returns
    -------
    Path
        The updated aircraft's XML file.
    """
    return augment(campaign.aircraft, effects, folder, name=f"{campaign.aircraft}-updated")


@dataclass
class HeldOutGap:
    """One held-out point: its condition and, per axis, the gap (residual over measured
    energy, mean over the axis's channels) of the model and of the updated aircraft."""

    index: int
    altitude: float
    speed: float
    before: dict[str, float] = field(default_factory=dict)
    after: dict[str, float] = field(default_factory=dict)
    # the flown aircraft itself re-flown: the gap a perfect model leaves (measured
    # surfaces and channels; known only in simulation)
    floor: dict[str, float] = field(default_factory=dict)
    # the whole record flown open loop from the trim, no offsets: {before|after|floor: {axis:
    # gap}}
    open_loop: dict[str, dict[str, float]] = field(default_factory=dict)
    # per corrected derivative: the exact values of the flown, model and updated aircraft
    derivatives: dict[str, dict[str, float]] = field(default_factory=dict)

    def shrink(self, axis: str) -> float:
        """(before - after) / before on ``axis``."""
        b, a = self.before.get(axis, math.nan), self.after.get(axis, math.nan)
        return (b - a) / b if b > 0 else math.nan


def held_out_gaps(campaign: Campaign, effects: list[AugmentEffect]) -> list[HeldOutGap]:
    """Fly every held-out point and its gap with the model, with the model plus the
    correction ``effects`` (the updated aircraft, with the point's mass and CG) and with
    the flown aircraft (the floor), window by window as the gap diagnosis re-flies
    (``window_gaps``), and over the whole record open loop (``open_loop``).

    Parameters
    ----------
    campaign : Campaign
        The campaign with its held-out points.
    effects : list[AugmentEffect]
        The correction effects.

    Returns
    -------
    list[HeldOutGap]
        One per held-out point: gaps per axis before, after and floor, window by window and
        open loop.
    """
    out = []
    for i, p in enumerate(campaign.held_out):
        gap = HeldOutGap(i, p.altitude, p.speed)
        _, record, _ = fly_held_out(campaign, i)
        with quiet(), contextlib.redirect_stdout(io.StringIO()):
            model = point_card(campaign, p, with_effects=False)
            data = dict(model.data)
            data["effect"] = [*data.get("effect", []), *(e.to_dict() for e in effects)]
            updated = card_from_dict(data, f"{campaign.path} (held-out point {i}, updated)")
            real = point_card(campaign, p)
            for key, card in (("before", model), ("after", updated), ("floor", real)):
                aircraft = augmented(card) if card.augmentation else card.aircraft
                getattr(gap, key).update(window_gaps(aircraft, record))
                flown = fly_record(aircraft, record)
                gap.open_loop[key] = {
                    axis: float(np.nanmean(list(gap_fractions(record, flown, outputs).values())))
                    for axis, outputs in AXIS_OUTPUTS.items()}
            values = {k: model_values(c)[1] for k, c in
                      (("flown", real), ("model", model), ("updated", updated))}
        gap.derivatives = {e.derivative: {k: float(v[e.derivative]) for k, v in values.items()}
                           for e in effects}
        out.append(gap)
    return out


def window_gaps(aircraft: str | Path, record: FlightRecord) -> dict[str, float]:
    """Per axis, the gap of ``aircraft`` on ``record``: the mean over the axis's maneuver
    windows (``identification.gap.segments``) of the mean over its channels, each window
    flown as the gap diagnosis's re-fly (``identification.gap.jsbsim.refly.fly_window``: start
    state, offsets refitted); NaN for an axis without a window or where every window
    departs.

    Parameters
    ----------
    aircraft : str or Path
        Aircraft name or XML path.
    record : FlightRecord
        The measured flight.

    Returns
    -------
    dict[str, float]
        Axis -> mean gap, 1 (NaN as above).
    """
    model = load(str(augment_cached(str(aircraft), [], CACHE, surface_drive=True)))
    altitude, speed = start_condition(record)
    trimmed = trim(model, max(altitude, 0.0), speed)
    out = {}
    for axis in AXIS_OUTPUTS:
        values = []
        for seg in segments([record], inputs=AXIS_INPUTS[axis]):
            flown = fly_window(model, trimmed, record, seg.record, axis)
            if flown.gap and not flown.departed:
                values.append(float(np.nanmean(list(flown.gap.values()))))
        out[axis] = float(np.mean(values)) if values else math.nan
    return out


def summary(fitted: list[Correction], gaps: list[HeldOutGap]) -> dict[str, Any]:
    """The corrections and the held-out gaps as plain data (update.json): per axis the
    mean gap before, after and of the flown aircraft itself (floor), the shrink
    (before - after) / before and the shrink of the model's part of the gap,
    (before - after) / (before - floor); the same means of the whole record flown open
    loop (``open_loop``); per corrected derivative the RMS over the held-out points of
    model minus flown and updated minus flown.

    Parameters
    ----------
    fitted : list[Correction]
        The fitted corrections.
    gaps : list[HeldOutGap]
        The held-out points' gaps.

    Returns
    -------
    dict[str, Any]
        The contents of update.json.
    """
    axes = list(AXIS_OUTPUTS)
    mean = {key: {a: float(np.nanmean([getattr(g, key).get(a, math.nan) for g in gaps]))
                  for a in axes} for key in ("before", "after", "floor")} if gaps else {}

    def ratio(a: str, floor: bool) -> float:
        if not mean:
            return math.nan
        b, f = mean["before"][a], mean["floor"][a] if floor else 0.0
        return (b - mean["after"][a]) / (b - f) if b - f > 0 else math.nan

    open_loop = {key: {a: float(np.nanmean([g.open_loop[key].get(a, math.nan) for g in gaps]))
                       for a in axes} for key in ("before", "after", "floor")} if gaps else {}
    names = sorted({n for g in gaps for n in g.derivatives})
    derivative_gap = {n: {k: float(np.sqrt(np.mean([(g.derivatives[n][k]
                                                      - g.derivatives[n]["flown"]) ** 2
                                                     for g in gaps if n in g.derivatives])))
                          for k in ("model", "updated")} for n in names}
    return {"corrections": [asdict(c) for c in fitted],
            "held_out": [asdict(g) | {"shrink": {a: g.shrink(a) for a in axes}} for g in gaps],
            "mean": mean,
            "shrink": {a: ratio(a, False) for a in axes},
            "shrink_above_floor": {a: ratio(a, True) for a in axes},
            "open_loop": open_loop,
            "derivative_gap": derivative_gap}
