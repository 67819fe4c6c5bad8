"""One test point of a campaign: fly it, reduce the record, identify, score.

``run_point(campaign, index)`` is a pure function of its arguments (a worker process, local
or on a Dask cluster, needs nothing else) and returns one row per identified derivative:
the Monte Carlo store's columns (``index`` is the point, ``truth`` the flown aircraft's
exact derivative, ``sigmas`` the error in standard errors) plus the point's condition,
its trim alpha (rad) and ``model``, the model aircraft's value at the same condition (the
JSBSim tables the campaign is to check; equal to the truth when the campaign flies the
model itself).
"""

from __future__ import annotations

import contextlib
import io
import math
from typing import Any

from threadpoolctl import threadpool_limits

from flightid.identification.data.reduction import reduce_record
from flightid.identification.evaluation.scoring import STATUS_ESTIMATED, record_truth, score
from flightid.identification.identify import identify
from flightid.scenarios.campaign.card import Campaign, TestPoint, point_card
from flightid.scenarios.cards import Card, fly_card, sub_seed, trim_card
from flightid.scenarios.montecarlo.study import FLOAT_COLUMNS, REALIZATION_ERRORS
from flightid.sim.jsbsim.model import quiet
from flightid.sim.jsbsim.truth import derivatives

STATUS_FAILED = "failed"


def point_seed(campaign: Campaign, index: int) -> int:
    """The seed of test point ``index`` (independent of the other points)."""
    return sub_seed(campaign.seed, f"campaign:{int(index)}")


def model_values(card: Card) -> tuple[float, dict[str, float]]:
    """(trim alpha in rad, the exact body-axis derivatives) of ``card``'s aircraft at its
    condition: the JSBSim tables' derivatives (``sim.jsbsim.truth.derivatives``)."""
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        model, trimmed = trim_card(card)
        values = derivatives(model, trimmed, axes="body").values
    return float(trimmed.alpha), dict(values)


def run_point(campaign: Campaign, index: int) -> list[dict[str, Any]]:
    """Fly, reduce, identify and score test point ``index``; never empty (a point that
    departs, cannot be trimmed or is refused by the method is one 'failed' row)."""
    with threadpool_limits(1):  # one BLAS thread: the parallelism is the points
        return _point_rows(campaign, index, campaign.points[int(index)])


def _point_rows(campaign: Campaign, index: int, point: TestPoint) -> list[dict[str, Any]]:
    seed = point_seed(campaign, index)
    base: dict[str, Any] = {"index": int(index), "seed": int(seed), **point.as_dict(),
                            "alpha": math.nan}
    try:
        card = point_card(campaign, point)
        with quiet(), contextlib.redirect_stdout(io.StringIO()):
            measured, truth_record = fly_card(card, seed)
        base["alpha"] = float(truth_record.meta.extra["truth"]["trim"]["alpha"])
        record = reduce_record(measured).record
        est = identify(record, campaign.method, campaign.model, **dict(campaign.options))
    except REALIZATION_ERRORS as exc:
        return [_failure(base, f"{type(exc).__name__}: {exc}")]
    if est.fit.get("converged") is False:
        return [_failure(base, "not converged")]
    truth = record_truth(truth_record)
    if card.augmentation and any(e.name not in ("mass_scale", "cg_offset")
                                 for e in card.augmentation):
        _, model = model_values(point_card(campaign, point, with_effects=False))
    else:
        model = truth
    rows = []
    for r in score(est, truth).rows:
        flown = flown_condition(record, r.name)
        rows.append({**base, **flown, "name": r.name, "truth": _num(r.truth),
                     "estimate": _num(r.estimate), "std": _num(r.std), "error": _num(r.error),
                     "sigmas": _num(r.sigmas), "status": r.status, "reason": r.reason or "",
                     "model": float(model.get(r.name, math.nan))})
    if not any(r["status"] == STATUS_ESTIMATED for r in rows):
        return [_failure(base, "the estimate scored no derivative")]
    return rows


# the record channel whose excursions carry a derivative's information, by its variable
VARIABLE_CHANNEL = {"alpha": "alpha", "beta": "beta", "p": "p", "q": "q", "r": "r",
                    "alphadot": "alpha", "de": "de", "da": "da", "dr": "dr"}


def flown_condition(record: Any, derivative: str) -> dict[str, float]:
    """The condition an estimate of ``derivative`` stands for: the airspeed (m/s) and
    alpha (rad) of the record averaged with the weight of its variable's squared
    excursion from the trim (its first sample), ``speed_flown`` and ``alpha_flown``.

    A least-squares slope of C on x over a record is the local slope averaged with the
    weight (x - x0)^2 (Morelli & Klein 2016 eq. 5.10 for one regressor), so where the
    derivative changes with the condition, the estimate belongs to this weighted mean,
    not to the trim: on twinotter-hidden-trend the phugoid after the elevator input put
    the sideslip-weighted airspeed 1.1 m/s above the 62 m/s trim, which moved Cn_beta by
    -0.0013 (10 of its standard errors). Without the channel: the record's mean."""
    var = derivative.partition("_")[2]
    channel = VARIABLE_CHANNEL.get(var)
    out = {}
    for key, name in (("speed_flown", "V"), ("alpha_flown", "alpha")):
        if name not in record:
            out[key] = math.nan
            continue
        values = record[name]
        if channel is None or channel not in record:
            out[key] = float(values.mean())
            continue
        x = record[channel]
        w = (x - x[0]) ** 2
        out[key] = float((values * w).sum() / w.sum()) if w.sum() > 0 else float(values.mean())
    return out


def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def _failure(base: dict[str, Any], reason: str) -> dict[str, Any]:
    row: dict[str, Any] = {**base, "name": "", "status": STATUS_FAILED, "reason": reason,
                           "model": math.nan, "speed_flown": math.nan,
                           "alpha_flown": math.nan}
    row.update({c: float("nan") for c in FLOAT_COLUMNS})
    return row


__all__ = ["model_values", "point_seed", "run_point"]
