"""A campaign's global model: one fit over every test point's record, maneuvers and
conditions pooled, by a method that fits several records at once.

NASA's global modeling identifies one model valid across the envelope from many
maneuvers (Morelli 1995; Morelli & Klein 2016 sec. 5.5): ``mof.fit_records`` is that fit,
the one ``flightid identify --method mof`` runs on a single record. The campaign re-flies
its points (``point.fly_point``: a pure function of the campaign and the index, so the
records are those its workers identified) and passes them to it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from flightid.identification.data.coefficients import channel_values
from flightid.identification.engine.metrics import r_squared, theil_inequality
from flightid.identification.estimate import Estimate
from flightid.identification.methods import mof, registry
from flightid.record import FlightRecord
from flightid.scenarios.campaign.card import Campaign
from flightid.scenarios.campaign.point import fly_held_out, fly_point

# their prediction of one coefficient on another record: (model, record, coefficient)
POOLED_PREDICT: dict[str, Callable[[Estimate, FlightRecord, str], np.ndarray]] = {
    mof.ID: mof.predict}
# the methods with a fit over several records: (records, model, options) -> one Estimate
POOLED: dict[str, Callable[[Sequence[FlightRecord], str, Any], Estimate]] = {
    mof.ID: mof.fit_records}


def has_global_model(campaign: Campaign) -> bool:
    """Whether the campaign's method fits one model over several records.

    Parameters
    ----------
    campaign : Campaign
        The campaign (its method).

    Returns
    -------
    bool
        True for a method that pools records.
    """
    return campaign.method in POOLED


def fit_global(campaign: Campaign, indices: Sequence[int]) -> Estimate:
    """One model over the records of the test points ``indices`` (the points that did not
    fail), by the campaign's method, model and options.

    Parameters
    ----------
    campaign : Campaign
        A campaign whose method has a pooled fit (``has_global_model``).
    indices : sequence of int
        The test points pooled.

    Returns
    -------
    Estimate
        Every coefficient's chosen terms (``fit['coefficients'][C]['steps']``), their
        values and standard errors, as the method gives for one record.
    """
    if not has_global_model(campaign):
        raise ValueError(f"method {campaign.method} fits one record at a time; a global "
                         f"model needs one of: {', '.join(POOLED)}")
    if not indices:
        raise ValueError("no test point to pool: every point failed")
    options = registry.get(campaign.method).make_options(campaign.options)
    records = [fly_point(campaign, i)[1] for i in indices]
    return POOLED[campaign.method](records, campaign.model, options)


def summary(est: Estimate, indices: Sequence[int]) -> dict[str, Any]:
    """The global model as plain data (global_model.json): the points pooled, every term
    with its value and standard error, and per coefficient the chosen terms, R^2 and
    predicted square error (PSE) of the fit and its number of samples.

    Parameters
    ----------
    est : Estimate
        The pooled estimate.
    indices : Sequence[int]
        Indices of the pooled test points.

    Returns
    -------
    dict[str, Any]
        The contents of global_model.json.
    """
    coefficients = est.fit.get("coefficients", {})
    return {"method": est.method, "points": [int(i) for i in indices],
            "terms": {n: {"estimate": float(est[n]), "std": float(est.std_of(n))}
                      for n in est.names},
            "coefficients": {c: {"terms": [n for n in est.names if n.startswith(c + "_")],
                                 **{k: v for k, v in fit.items()
                                    if k in ("R2", "PSE", "N")}}
                             for c, fit in coefficients.items()}}


def validate(campaign: Campaign, est: Estimate) -> dict[str, Any]:
    """The global model's prediction of the held-out points' coefficients
    (``[[held_out]]``, flown and reduced as for the database update: ``point.fly_held_out``).

    Model validation by prediction on maneuvers the fit never saw (Morelli & Klein 2016,
    model validation): the model is fixed, nothing is refitted, not even the bias (a
    global model holds the levels across the envelope). Per coefficient, R^2 and the Theil
    inequality coefficient of the measured against the predicted time history, pooled over
    the held-out points and per point.

    Parameters
    ----------
    campaign : Campaign
        The campaign whose global model ``est`` is (``fit_global``).
    est : Estimate
        The global model.

    Returns
    -------
    dict
        ``points``: the held-out conditions (altitude m, speed m/s); ``coefficients``:
        {C: {"R2", "Theil", "per_point": [{"R2", "Theil"}, ...]}}; empty without held-out
        points.
    """
    if not campaign.held_out:
        return {}
    predict = POOLED_PREDICT[campaign.method]
    records = [fly_held_out(campaign, i)[1] for i in range(len(campaign.held_out))]
    out: dict[str, Any] = {
        "points": [{"altitude": p.altitude, "speed": p.speed} for p in campaign.held_out],
        "coefficients": {}}
    for c in est.fit.get("coefficients", {}):
        pairs = [(channel_values(r, c), predict(est, r, c)) for r in records]
        y, m = (np.concatenate(v) for v in zip(*pairs, strict=True))
        out["coefficients"][c] = {
            "R2": float(r_squared(y, m)), "Theil": float(theil_inequality(y, m)),
            "per_point": [{"R2": float(r_squared(a, b)), "Theil": float(theil_inequality(a, b))}
                          for a, b in pairs]}
    return out
