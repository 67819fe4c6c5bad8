"""The model's curve between the test points: the JSBSim tables' derivatives along the
campaign's path through the envelope.

The points are ordered by the campaign's x (speed, altitude, flaps, mass, cg_x, or the
trim alpha) and joined by straight lines in condition space (altitude, speed, flaps,
mass, CG); ``STEPS`` conditions are taken on each segment. At each, the model aircraft
(the flight card's aircraft with the condition's mass and CG, without the campaign's
other effects) is trimmed and its exact derivatives taken (``sim.jsbsim.truth.derivatives``,
body axes), so the curve is what the aircraft's tables say between the flight points.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import math
from typing import Any

import numpy as np
import pandas as pd

from flightid.scenarios.campaign.card import Campaign, TestPoint, point_card
from flightid.scenarios.campaign.point import model_values
from flightid.scenarios.cards import trim_card
from flightid.sim.jsbsim.model import quiet
from flightid.sim.jsbsim.trim import TrimError

STEPS = 3  # conditions per segment between two neighbouring points (the first included)
MAX_CONDITIONS = 40  # the curve's conditions at most (fewer steps for many points)
CURVE_COLUMNS = ("condition", "altitude", "speed", "flaps", "mass", "cg_x", "alpha", "name",
                 "model")


def ordered_points(campaign: Campaign, alphas: dict[int, float] | None = None
                   ) -> list[TestPoint]:
    """The campaign's points ordered by its x (the trim alpha from ``alphas``, {point
    index: rad}, when x is alpha), duplicates of a condition once.

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    alphas : dict[int, float] or None, optional
        Point index -> trim angle of attack, rad; needed when x is alpha.

    Returns
    -------
    list[TestPoint]
        The ordered, distinct points (those without a finite x left out).
    """
    def key(item: tuple[int, TestPoint]) -> float:
        i, p = item
        if campaign.x == "alpha":
            return (alphas or {}).get(i, math.nan)
        return float(getattr(p, campaign.x))

    items = [it for it in enumerate(campaign.points) if math.isfinite(key(it))]
    out: list[TestPoint] = []
    for _, p in sorted(items, key=key):
        if p not in out:
            out.append(p)
    return out


def path_conditions(points: list[TestPoint], steps: int = STEPS) -> list[TestPoint]:
    """Conditions on the straight segments between consecutive ``points``: ``steps`` per
    segment (the segment's first point included) and the last point.

    Parameters
    ----------
    points : list[TestPoint]
        Ordered test points.
    steps : int, optional
        Conditions per segment; reduced to keep the total within ``MAX_CONDITIONS``.

    Returns
    -------
    list[TestPoint]
        The interpolated conditions.
    """
    if len(points) < 2:
        return list(points)
    steps = max(1, min(steps, (MAX_CONDITIONS - 1) // (len(points) - 1)))
    out = []
    for a, b in zip(points[:-1], points[1:], strict=True):
        for s in np.arange(steps) / steps:
            out.append(TestPoint(*(float(x + s * (y - x)) for x, y in
                                   zip(_values(a), _values(b), strict=True))))
    out.append(points[-1])
    return out


def _values(p: TestPoint) -> tuple[float, ...]:
    return p.altitude, p.speed, p.flaps, p.mass, p.cg_x


def model_curve(campaign: Campaign, alphas: dict[int, float] | None = None,
                steps: int = STEPS) -> pd.DataFrame:
    """The model's derivatives along the campaign's path: one row per (condition,
    derivative), columns ``CURVE_COLUMNS`` (``alpha`` the model's trim alpha, rad). A
    condition the model cannot be trimmed at is left out.

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    alphas : dict[int, float] or None, optional
        Point index -> trim angle of attack, rad, for ordering when x is alpha.
    steps : int, optional
        Conditions per segment of the path.

    Returns
    -------
    pandas.DataFrame
        The model curve.
    """
    rows: list[dict[str, Any]] = []
    for k, cond in enumerate(path_conditions(ordered_points(campaign, alphas), steps)):
        try:
            alpha, values = model_values(point_card(campaign, cond, with_effects=False))
        except TrimError:
            continue
        for name, value in values.items():
            rows.append({"condition": k, **cond.as_dict(), "alpha": alpha, "name": name,
                         "model": float(value)})
    return pd.DataFrame(rows, columns=list(CURVE_COLUMNS))


# the secant search for the speed whose trim alpha is a given alpha: at most this many
# trims, stopped within this many rad
ALPHA_TRIMS = 6
ALPHA_TOLERANCE = 1e-5


def model_at(campaign: Campaign, point: TestPoint, x: float) -> dict[str, float]:
    """The model aircraft's derivatives (body axes; ``sim.jsbsim.truth.derivatives``) on
    the campaign's path at the point where the campaign's x takes the value ``x``: the
    point's condition with its airspeed set to ``x`` (m/s) when x is speed; with the
    airspeed at which the model trims at alpha ``x`` (rad) when x is alpha (secant on the
    trim alpha against airspeed); and the point itself for any other x.

    The curve the database update relocates is the model trimmed along the path
    (``model_curve``); an estimate stands for its flown condition
    (``point.flown_condition``), so the model's value it is compared with is the curve's
    there, not at the trim.

    Parameters
    ----------
    campaign : Campaign
        The campaign (its x and flight card).
    point : TestPoint
        The test point the estimate belongs to.
    x : float
        The value of the campaign's x (m/s for speed, rad for alpha).

    Returns
    -------
    dict
        {derivative: value}, per rad and per unit nondimensional rate. Raises
        ``TrimError`` where the model cannot be trimmed.
    """
    if campaign.x == "speed":
        return model_values(point_card(campaign, dataclasses.replace(point, speed=float(x)),
                                       with_effects=False))[1]
    if campaign.x != "alpha":
        return model_values(point_card(campaign, point, with_effects=False))[1]
    speeds = [point.speed, point.speed * 1.02]
    alphas = [_trim_alpha(campaign, point, v) for v in speeds]
    for _ in range(ALPHA_TRIMS):
        if abs(alphas[-1] - x) < ALPHA_TOLERANCE or alphas[-1] == alphas[-2]:
            break
        v = speeds[-1] + (x - alphas[-1]) * (speeds[-1] - speeds[-2]) / (alphas[-1]
                                                                          - alphas[-2])
        speeds.append(float(v))
        alphas.append(_trim_alpha(campaign, point, v))
    return model_values(point_card(campaign, dataclasses.replace(point, speed=speeds[-1]),
                                   with_effects=False))[1]


def _trim_alpha(campaign: Campaign, point: TestPoint, speed: float) -> float:
    card = point_card(campaign, dataclasses.replace(point, speed=float(speed)),
                      with_effects=False)
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        return float(trim_card(card)[1].alpha)
