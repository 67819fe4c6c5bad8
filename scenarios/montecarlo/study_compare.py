"""``study-compare``: several finished Monte Carlo studies side by side, as a design
comparison of their folders (``design.Comparison``): each derivative's scatter and mean
bound by study, each study's scatter ratios to the first with their intervals (paired
bootstrap where both have 20 or more realizations, realization i of each paired: the same
seeds when the studies share their base seed, independent draws otherwise, for which
resampling pairs is valid too), and the ratio of the mean scatter / |truth|."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from flightid.scenarios.montecarlo import load
from flightid.scenarios.montecarlo.design.comparison import Comparison, DesignResult
from flightid.scenarios.montecarlo.design.experiment import DesignSettings
from flightid.scenarios.montecarlo.store import SUMMARY_COLUMNS, read_description
from flightid.scenarios.montecarlo.summary import summarize


def study_names(dirs: Sequence[str | Path]) -> list[str]:
    """A short name per study: its folder's name, with its parent's where two clash.

    Parameters
    ----------
    dirs : Sequence[str or Path]
        Study folders.

    Returns
    -------
    list[str]
        One name per folder, in order.
    """
    names = [Path(d).resolve().name for d in dirs]
    return [f"{Path(d).resolve().parent.name}/{n}" if names.count(n) > 1 else n
            for d, n in zip(dirs, names, strict=True)]


def compare_studies(dirs: Sequence[str | Path]) -> Comparison:
    """The studies in ``dirs`` (two or more, each a folder holding study.json and rows) as
    a Comparison, one result per study in the given order; costs not known to a study
    (flight and input time, energy, peak) are NaN.

    Parameters
    ----------
    dirs : Sequence[str or Path]
        Two or more study folders.

    Returns
    -------
    Comparison
        One result per study, named by :func:`study_names`.
    """
    if len(dirs) < 2:
        raise ValueError("study-compare needs two or more study folders")
    descriptions = [read_description(d)["description"] for d in dirs]
    first = descriptions[0]
    out = Comparison(str(first.get("card", "")), "", str(first.get("method", "")),
                     str(first.get("model", "")), int(first.get("n", 0)), "", "",
                     DesignSettings())
    for d, name in zip(dirs, study_names(dirs), strict=True):
        rows = load(d, SUMMARY_COLUMNS)
        if rows.empty:
            raise ValueError(f"{d}: the study has no finished realization")
        out.results.append(DesignResult(kind=name, flight_time=math.nan,
                                        input_time=math.nan, energy=math.nan, peak=math.nan,
                                        summary=summarize(rows), study_dir=str(d)))
    return out


def against_first(comparison: Comparison) -> dict[str, Any]:
    """Every other study against the first: per-derivative scatter ratios with intervals
    (``Comparison.scatter_ratios``) and the mean scatter / |truth| ratio with its paired
    interval (``Comparison.mean_relative_scatter``).

    Parameters
    ----------
    comparison : Comparison
        The studies, first one the base.

    Returns
    -------
    dict[str, Any]
        Study name -> {"ratios", "mean_relative_scatter"}.
    """
    kinds = [r.kind for r in comparison.results]
    base = kinds[0]
    return {k: {"ratios": comparison.scatter_ratios(k, base),
                "mean_relative_scatter": comparison.mean_relative_scatter(k, base)}
            for k in kinds[1:]}
