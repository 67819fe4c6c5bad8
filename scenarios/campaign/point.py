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
from flightid.identification.methods import registry
from flightid.record import FlightRecord
from flightid.scenarios.campaign.card import MODEL_START, Campaign, TestPoint, point_card
from flightid.scenarios.cards import Card, fly_card, sub_seed, trim_card
from flightid.scenarios.montecarlo.study import FLOAT_COLUMNS, REALIZATION_ERRORS
from flightid.sim.jsbsim.model import quiet
from flightid.sim.jsbsim.truth import derivatives

STATUS_FAILED = "failed"


def point_seed(campaign: Campaign, index: int) -> int:
    """The seed of test point ``index`` (independent of the other points).

    Parameters
    ----------
    campaign : Campaign
        The campaign (its seed).
    index : int
        Test point index.

    Returns
    -------
    int
        The point's seed.
    """
    return sub_seed(campaign.seed, f"campaign:{int(index)}")


def model_values(card: Card) -> tuple[float, dict[str, float]]:
    """(trim alpha in rad, the exact body-axis derivatives) of ``card``'s aircraft at its
    condition: the JSBSim tables' derivatives (``sim.jsbsim.truth.derivatives``).

    Parameters
    ----------
    card : Card
        Flight card of the point.

    Returns
    -------
    tuple[float, dict[str, float]]
        Trim angle of attack, rad, and derivative name -> value (per rad, rates
        nondimensional).
    """
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        model, trimmed = trim_card(card)
        values = derivatives(model, trimmed, axes="body").values
    return float(trimmed.alpha), dict(values)


def run_point(campaign: Campaign, index: int) -> list[dict[str, Any]]:
    """Fly, reduce, identify and score test point ``index``; never empty (a point that
    departs, cannot be trimmed or is refused by the method is one 'failed' row).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    index : int
        Test point index.

    Returns
    -------
    list[dict[str, Any]]
        Rows of the estimates table, one per derivative (or one 'failed' row).
    """
    with threadpool_limits(1):  # one BLAS thread: the parallelism is the points
        return _point_rows(campaign, index, campaign.points[int(index)])


def run_point_from(starts: dict[int, tuple[int, dict[str, float]]], campaign: Campaign,
                   index: int) -> list[dict[str, Any]]:
    """``run_point`` with the fit started from a neighbour's estimates (campaign field
    ``start = "neighbour"``): ``starts[index]`` is (the neighbour, its estimates by
    derivative name), from ``neighbour.neighbour_starts``; a point not in ``starts``
    starts where the method starts it. A module-level function of picklable arguments
    (``functools.partial(run_point_from, starts)`` is an executor's task).

    Parameters
    ----------
    starts : dict[int, tuple[int, dict[str, float]]]
        Point index -> (neighbour index, its estimates by derivative name).
    campaign : Campaign
        The campaign.
    index : int
        Test point index.

    Returns
    -------
    list[dict[str, Any]]
        Rows of the estimates table, as :func:`run_point`.
    """
    start = starts.get(int(index))
    with threadpool_limits(1):
        return _point_rows(campaign, index, campaign.points[int(index)], start)


def fly_point(campaign: Campaign, index: int) -> tuple[Card, FlightRecord, FlightRecord]:
    """Test point ``index`` flown with its own seed: (its flight card, the measured record
    after the standard data reduction, the truth record). A pure function of the campaign
    and the index: the same records in a worker and in the process that pools them.
    Raises what ``fly_card`` and ``reduce_record`` raise (``REALIZATION_ERRORS``).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    index : int
        Test point index.

    Returns
    -------
    tuple[Card, FlightRecord, FlightRecord]
        (flight card, reduced measured record, truth record).
    """
    card = point_card(campaign, campaign.points[int(index)])
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        measured, truth_record = fly_card(card, point_seed(campaign, index))
    return card, reduce_record(measured).record, truth_record


def held_out_seed(campaign: Campaign, index: int) -> int:
    """The seed of held-out point ``index`` (independent of the test points).

    Parameters
    ----------
    campaign : Campaign
        The campaign (its seed).
    index : int
        Held-out point index.

    Returns
    -------
    int
        The held-out point's seed.
    """
    return sub_seed(campaign.seed, f"held_out:{int(index)}")


def fly_held_out(campaign: Campaign, index: int) -> tuple[Card, FlightRecord, FlightRecord]:
    """Held-out point ``index`` (``[[held_out]]``) flown with the flown aircraft (the
    campaign's effects included) and its own seed: (its flight card, the measured record
    after the standard data reduction, the truth record), as ``fly_point`` flies a test
    point.

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    index : int
        Held-out point index.

    Returns
    -------
    tuple[Card, FlightRecord, FlightRecord]
        (flight card, reduced measured record, truth record).
    """
    card = point_card(campaign, campaign.held_out[int(index)])
    with quiet(), contextlib.redirect_stdout(io.StringIO()):
        measured, truth_record = fly_card(card, held_out_seed(campaign, index))
    return card, reduce_record(measured).record, truth_record


def _point_rows(campaign: Campaign, index: int, point: TestPoint,
                neighbour: tuple[int, dict[str, float]] | None = None
                ) -> list[dict[str, Any]]:
    seed = point_seed(campaign, index)
    base: dict[str, Any] = {"index": int(index), "seed": int(seed), **point.as_dict(),
                            "alpha": math.nan,
                            "start_from": float(neighbour[0]) if neighbour else math.nan}
    try:
        card, record, truth_record = fly_point(campaign, index)
        base["alpha"] = float(truth_record.meta.extra["truth"]["trim"]["alpha"])
        truth = record_truth(truth_record)
        if card.augmentation and any(e.name not in ("mass_scale", "cg_offset")
                                     for e in card.augmentation):
            _, model = model_values(point_card(campaign, point, with_effects=False))
        else:
            model = truth
        options = dict(campaign.options)
        if campaign.start == "model":
            options["start"] = model_start(campaign, model)
        elif campaign.start == "neighbour" and neighbour:
            # the neighbour's flight estimates; what it did not estimate, from the tables
            options["start"] = model_start(campaign, {**model, **neighbour[1]})
        est = identify(record, campaign.method, campaign.model, **options)
    except REALIZATION_ERRORS as exc:
        return [_failure(base, f"{type(exc).__name__}: {exc}")]
    if est.fit.get("converged") is False:
        return [_failure(base, "not converged")]
    rows = []
    for r in score(est, truth).rows:
        flown = flown_condition(record, r.name)
        rows.append({**base, **flown, "name": r.name, "truth": _num(r.truth),
                     "estimate": _num(r.estimate), "std": _num(r.std), "error": _num(r.error),
                     "sigmas": _num(r.sigmas), "status": r.status, "reason": r.reason or "",
                     "model": float(model.get(r.name, math.nan)),
                     "iterations": float(est.fit.get("iterations", math.nan))})
    if not any(r["status"] == STATUS_ESTIMATED for r in rows):
        return [_failure(base, "the estimate scored no derivative")]
    return rows


def model_start(campaign: Campaign, model: dict[str, float]) -> dict[str, float]:
    """The start values of a point's fit from the model aircraft's derivatives at the
    point (``model``: body axes, per rad, rates nondimensional): the value of every
    parameter the method takes a start for that the tables give (campaign field
    ``start = "model"``). The model's tables are the a priori values a flight test starts
    from (Jategaonkar 2015 ch. 4: start values from wind-tunnel data); the fit
    then converges to the same minimum as from equation error's start.

    Parameters
    ----------
    campaign : Campaign
        The campaign (its method, model and options).
    model : dict[str, float]
        Model aircraft's derivatives at the point, body axes.

    Returns
    -------
    dict[str, float]
        Parameter name -> start value, for the finite ones the method takes.
    """
    spec = registry.get(campaign.method)
    names = MODEL_START[campaign.method](campaign.model, spec.make_options(campaign.options))
    return {n: float(model[n]) for n in names if n in model and math.isfinite(model[n])}


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
    the sideslip-weighted airspeed 0.76 m/s above the 68 m/s trim, which moves Cn_beta by
    -0.0009 (5 of its standard errors). Without the channel: the record's mean.

    Parameters
    ----------
    record : FlightRecord
        The flight (channels ``V``, m/s, and ``alpha``, rad).
    derivative : str
        Derivative name, e.g. ``"Cn_beta"``; the part after ``_`` picks the variable.

    Returns
    -------
    dict[str, float]
        ``"speed_flown"`` (m/s) and ``"alpha_flown"`` (rad); NaN where the record lacks the
        channel.
    """
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
                           "alpha_flown": math.nan, "iterations": math.nan}
    row.update({c: float("nan") for c in FLOAT_COLUMNS})
    return row


__all__ = ["fly_held_out", "fly_point", "held_out_seed", "model_start", "model_values",
           "point_seed", "run_point", "run_point_from"]
