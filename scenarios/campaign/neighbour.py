"""Warm starts from a flown neighbour (campaign field ``start = "neighbour"``).

A point's fit starts from the estimates of the nearest test point already flown, as a
flight-test programme carries the last condition's derivatives into the next one
(Jategaonkar 2015 ch. 4: good start values). The points stay pure functions of the
campaign: they run in two waves fixed by the card alone.

- The anchors: the points ordered by the campaign's x (speed for x = alpha, whose trim
  value is known only once flown) and then by the other fields, every other one from the
  first. They start where the method starts them.
- The others: each starts from the estimates of the nearest anchor that did not fail,
  in the conditions scaled by their range over the campaign (altitude, speed, flaps,
  mass, CG; a field that does not vary is left out), the lower index on a tie. What the
  anchor did not estimate (the biases C*_0) starts from the model's tables at the point.

A rerun continues either wave from the store.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import pandas as pd

from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.scenarios.campaign.card import Campaign

FIELDS = ("altitude", "speed", "flaps", "mass", "cg_x")


def _scaled(campaign: Campaign) -> list[tuple[float, ...]]:
    """Each point's condition with every field divided by its range over the campaign."""
    rows = [p.as_dict() for p in campaign.points]
    spans = {f: max(r[f] for r in rows) - min(r[f] for r in rows) for f in FIELDS}
    used = [f for f in FIELDS if spans[f] > 0]
    return [tuple(r[f] / spans[f] for f in used) for r in rows]


def anchors(campaign: Campaign) -> list[int]:
    """The points that start where the method starts them: ordered by the campaign's x,
    then by altitude, speed, flaps, mass and CG, every other one from the first.

    Parameters
    ----------
    campaign : Campaign
        The campaign.

    Returns
    -------
    list of int
        The anchors' indices, ascending.
    """
    first = "speed" if campaign.x == "alpha" else campaign.x
    keys = (first, *(f for f in FIELDS if f != first))
    order = sorted(range(campaign.n),
                   key=lambda i: (*(campaign.points[i].as_dict()[k] for k in keys), i))
    return sorted(order[0::2])


def nearest(campaign: Campaign, index: int, flown: Sequence[int]) -> int | None:
    """The point of ``flown`` nearest to point ``index`` in the scaled conditions (the
    lower index on a tie); None when ``flown`` is empty.

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    index : int
        The point that is to start.
    flown : sequence of int
        The candidate neighbours (anchors that did not fail).

    Returns
    -------
    int or None
        The neighbour's index.
    """
    if not flown:
        return None
    x = _scaled(campaign)
    return min(flown, key=lambda j: (math.dist(x[index], x[j]), j))


def neighbour_starts(campaign: Campaign, estimates: pd.DataFrame, indices: Sequence[int]
                     ) -> dict[int, tuple[int, dict[str, float]]]:
    """For each point of ``indices``: (its neighbour, the neighbour's estimates by
    derivative name), from the stored rows of the anchors (``estimates``: the campaign's
    rows, ``index``, ``name``, ``estimate``, ``status``). A point with no anchor that
    estimated anything is left out (it starts where the method starts it).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    estimates : pandas.DataFrame
        The rows stored so far.
    indices : sequence of int
        The points that are to start from a neighbour.

    Returns
    -------
    dict
        {index: (neighbour index, {derivative: estimate})}.
    """
    ok = estimates[estimates["status"] == STATUS_ESTIMATED]
    values: Mapping[int, dict[str, float]] = {
        int(i): dict(zip(g["name"], map(float, g["estimate"]), strict=True))
        for i, g in ok.groupby("index")}
    flown = sorted(set(values) & set(anchors(campaign)))
    out = {}
    for i in indices:
        j = nearest(campaign, int(i), flown)
        if j is not None:
            out[int(i)] = (j, values[j])
    return out


__all__ = ["anchors", "nearest", "neighbour_starts"]
