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

from flightid.identification.data_reduction import reduce_record
from flightid.identification.identify import identify
from flightid.identification.scoring import STATUS_ESTIMATED, record_truth, score
from flightid.scenarios.campaign.card import Campaign, TestPoint, point_card
from flightid.scenarios.cards import Card, fly_card, sub_seed, trim_card
from flightid.scenarios.montecarlo.study import FLOAT_COLUMNS, REALIZATION_ERRORS
from flightid.sim.model import quiet
from flightid.sim.truth import derivatives

STATUS_FAILED = "failed"


def point_seed(campaign: Campaign, index: int) -> int:
    """The seed of test point ``index`` (independent of the other points)."""
    return sub_seed(campaign.seed, f"campaign:{int(index)}")


def model_values(card: Card) -> tuple[float, dict[str, float]]:
    """(trim alpha in rad, the exact body-axis derivatives) of ``card``'s aircraft at its
    condition: the JSBSim tables' derivatives (``sim.truth.derivatives``)."""
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
        rows.append({**base, "name": r.name, "truth": _num(r.truth),
                     "estimate": _num(r.estimate), "std": _num(r.std), "error": _num(r.error),
                     "sigmas": _num(r.sigmas), "status": r.status, "reason": r.reason or "",
                     "model": float(model.get(r.name, math.nan))})
    if not any(r["status"] == STATUS_ESTIMATED for r in rows):
        return [_failure(base, "the estimate scored no derivative")]
    return rows


def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def _failure(base: dict[str, Any], reason: str) -> dict[str, Any]:
    row: dict[str, Any] = {**base, "name": "", "status": STATUS_FAILED, "reason": reason,
                           "model": math.nan}
    row.update({c: float("nan") for c in FLOAT_COLUMNS})
    return row


__all__ = ["model_values", "point_seed", "run_point"]
