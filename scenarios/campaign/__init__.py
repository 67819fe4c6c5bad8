"""Flight-test campaigns: a matrix of test points flown with one flight card's maneuvers,
every point identified, the estimates set against the model's tables across the envelope.

    from flightid.scenarios import campaign
    result = campaign.run("twinotter-envelope", "campaigns/twinotter")

Modules: ``card`` (the campaign card), ``point`` (fly, reduce, identify, score one point),
``curve`` (the model's derivatives between the points), ``report`` (DIR/report.html),
``update`` (the database update), ``global_model`` (one model over every point),
``neighbour`` (warm starts from a flown neighbour).
The points run on the Monte Carlo executors (local processes or Dask) and are stored as
the Monte Carlo store stores realizations (one Parquet file per point, atomically), so a
rerun continues. docs/campaign.md.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import pandas as pd

from flightid.identification.evaluation.scoring import STATUS_ESTIMATED
from flightid.scenarios.campaign import neighbour
from flightid.scenarios.campaign.card import Campaign, TestPoint, load_campaign, point_card
from flightid.scenarios.campaign.curve import model_curve
from flightid.scenarios.campaign.global_model import fit_global, has_global_model, validate
from flightid.scenarios.campaign.global_model import summary as global_summary
from flightid.scenarios.campaign.point import run_point, run_point_from
from flightid.scenarios.campaign.report import PointScore, point_scores, write_report
from flightid.scenarios.campaign.update import (
    correction_effects,
    corrections,
    flown_model,
    held_out_gaps,
    summary,
    write_updated,
)
from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.executors import dask_client, run_dask, run_local

ESTIMATES = "estimates.parquet"
CURVE = "model_curve.parquet"
UPDATE = "update.json"
GLOBAL = "global_model.json"

__all__ = ["Campaign", "CampaignResult", "TestPoint", "load_campaign", "point_card", "run"]


@dataclass
class CampaignResult:
    """A finished campaign: its folder, the per-point rows, the model curve, the scores."""

    folder: Path
    campaign: Campaign
    estimates: pd.DataFrame
    curve: pd.DataFrame
    scores: list[PointScore]
    report: Path
    update: dict | None = None  # corrections and held-out gaps (``update.summary``)
    aircraft: Path | None = None  # the updated aircraft's XML
    global_model: dict | None = None  # one model over every point (``global_model``)


def run(card: str | Path | Campaign, output: str | Path, workers: int | None = None,
        dask_address: str | None = None, dask_scheduler_file: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        update_aircraft: str | Path | None = None) -> CampaignResult:
    """Fly and identify every test point of ``card`` not yet stored in ``output``, then
    write OUTPUT/estimates.parquet (one row per point and derivative), OUTPUT/
    model_curve.parquet and OUTPUT/report.html. ``workers`` local processes (default one
    per CPU) or a Dask scheduler; ``progress(done, total)`` after each point. A folder
    holding another campaign is refused (``store.StudyMismatch``). ``update_aircraft``:
    write the model aircraft with its tables relocated to the flight points there, fly the
    held-out points and put the gap before and after into OUTPUT/update.json. A method
    that fits several records at once (``mof``) also fits one global model over every
    point's record (``global_model``), written to OUTPUT/global_model.json with its
    prediction of the held-out points (``global_model.validate``).

    Parameters
    ----------
    card : str or Path or Campaign
        Campaign card path, library campaign name or a loaded campaign.
    output : str or Path
        Output folder.
    workers : int or None, optional
        Local worker processes; None uses one per CPU.
    dask_address : str or None, optional
        Dask scheduler address; None runs locally unless ``dask_scheduler_file`` is given.
    dask_scheduler_file : str or None, optional
        Dask scheduler file.
    progress : callable or None, optional
        ``progress(done, total)``, points, after each point.
    update_aircraft : str or Path or None, optional
        Where to write the updated model aircraft; None updates nothing.

    Returns
    -------
    CampaignResult
        Folder, estimates, model curve, scores, report path and, with ``update_aircraft``,
        the update summary and aircraft XML.
    """
    campaign = card if isinstance(card, Campaign) else load_campaign(card)
    folder = Path(output)

    def keep(index: int, rows: list[dict]) -> None:
        store.write_realization(folder, index, rows)

    if dask_address is not None or dask_scheduler_file is not None:
        with dask_client(dask_address, dask_scheduler_file) as client:
            store.open_study(folder, campaign)  # type: ignore[arg-type]
            key = f"flightid-campaign-{campaign.identity()['card_sha256'][:12]}"
            for todo, task, offset in _waves(campaign, folder):
                run_dask(campaign, todo, keep, client, _offset(progress, offset, campaign.n),
                         task=task, key=f"{key}-{offset}")
    else:
        store.open_study(folder, campaign)  # type: ignore[arg-type]
        for todo, task, offset in _waves(campaign, folder):
            run_local(campaign, todo, keep, workers, _offset(progress, offset, campaign.n),
                      task=task)
    df = store.load(folder)
    df = df[df["index"] < campaign.n].reset_index(drop=True)
    df.to_parquet(folder / ESTIMATES, index=False)
    curve = _curve(campaign, df, folder)
    pooled = _global_model(campaign, df, folder)
    notes = _global_notes(pooled)
    if update_aircraft is None:
        report = write_report(folder, campaign, df, curve, notes=notes)
        return CampaignResult(folder, campaign, df, curve, point_scores(df), report,
                              global_model=pooled)
    flown = flown_model(campaign, df)
    fitted = corrections(campaign, flown)
    effects = correction_effects(campaign, flown, fitted)
    xml = write_updated(campaign, effects, update_aircraft)
    result = summary(fitted, held_out_gaps(campaign, effects))
    result["aircraft"] = str(xml)
    result["effects"] = [e.to_dict() for e in effects]
    (folder / UPDATE).write_text(json.dumps(result, indent=2, default=str) + "\n")
    report = write_report(folder, campaign, df, curve, notes=notes + _notes(result),
                          updated=updated_curve(campaign, curve, effects))
    return CampaignResult(folder, campaign, df, curve, point_scores(df), report, result, xml,
                          pooled)


def _waves(campaign: Campaign, folder: Path) -> Iterator[tuple[list[int], Callable, int]]:
    """The points still to fly, as (indices, task, points done before them): one wave, or
    with ``start = "neighbour"`` the anchors and then the others, each started from its
    nearest anchor's stored estimates (``neighbour``)."""
    done = store.done(folder)
    todo = sorted(set(range(campaign.n)) - done)
    if campaign.start != "neighbour":
        yield todo, run_point, len(done)
        return
    anchors = set(neighbour.anchors(campaign))
    first = [i for i in todo if i in anchors]
    yield first, run_point, len(done)
    rest = [i for i in todo if i not in anchors]
    if rest:
        starts = neighbour.neighbour_starts(campaign, store.load(folder), rest)
        yield rest, partial(run_point_from, starts), len(done) + len(first)


def _offset(progress: Callable[[int, int], None] | None, before: int, total: int
            ) -> Callable[[int, int], None] | None:
    """``progress`` of a wave, counted over the whole campaign."""
    if progress is None:
        return None
    return lambda finished, _: progress(before + finished, total)


def _global_model(campaign: Campaign, df: pd.DataFrame, folder: Path) -> dict | None:
    """With a method that fits several records (``global_model.POOLED``): one model over
    the records of every point that did not fail, written to OUTPUT/global_model.json."""
    if not has_global_model(campaign):
        return None
    estimated = df["status"] == STATUS_ESTIMATED
    indices = sorted(int(i) for i in df.loc[estimated, "index"].unique())
    est = fit_global(campaign, indices)
    result = global_summary(est, indices)
    result["held_out"] = validate(campaign, est)
    (folder / GLOBAL).write_text(json.dumps(result, indent=2, default=str) + "\n")
    return result


def _global_notes(pooled: dict | None) -> list[str]:
    if pooled is None:
        return []
    lines = [f"global model over points {', '.join(map(str, pooled['points']))}: "
             + "; ".join(f"{c} {len(v['terms'])} terms (R^2 {v.get('R2', float('nan')):.3f})"
                         for c, v in pooled["coefficients"].items())]
    held = pooled.get("held_out") or {}
    if held:
        lines.append(f"global model predicting the {len(held['points'])} held-out points "
                     "(nothing refitted): " + "; ".join(
                         f"{c} R^2 {v['R2']:.3f}, Theil {v['Theil']:.3f}"
                         for c, v in held["coefficients"].items()))
    return lines


def updated_curve(campaign: Campaign, curve: pd.DataFrame, effects: list) -> pd.DataFrame:
    """The model curve with the correction effects' deltas added (what the updated
    aircraft's tables say along the campaign's path).

    Parameters
    ----------
    campaign : Campaign
        The campaign.
    curve : pandas.DataFrame
        The model curve (columns ``name``, ``model``, ``speed``, ``alpha``).
    effects : list
        The correction effects.

    Returns
    -------
    pandas.DataFrame
        A copy of ``curve`` with corrected ``model`` values.
    """
    out = curve.copy()
    for e in effects:
        rows = out["name"] == e.derivative
        if hasattr(e, "at"):
            x = out.loc[rows, "speed" if e.schedule == "airspeed" else "alpha"]
            out.loc[rows, "model"] += [e.at(float(v)) for v in x]
        else:
            out.loc[rows, "model"] += e.delta
    return out


def _notes(result: dict) -> list[str]:
    kept = [c for c in result["corrections"] if c["form"] != "none"]
    lines = [f"database update: {len(kept)} derivative(s) corrected: " + ", ".join(
        f"{c['name']} ({c['form']})" for c in kept)]
    for axis, shrink in result["shrink"].items():
        if result["mean"]:
            m = result["mean"]
            lines.append(f"held-out gap, {axis}: {m['before'][axis]:.4f} before, "
                         f"{m['after'][axis]:.4f} after ({100 * shrink:.0f} % smaller); the "
                         f"flown aircraft itself {m['floor'][axis]:.4f}: the model's part "
                         f"{100 * result['shrink_above_floor'][axis]:.0f} % smaller (each "
                         "maneuver window re-flown as the gap diagnosis does)")
        if result.get("open_loop"):
            o = result["open_loop"]
            lines.append(f"held-out gap, {axis}, whole record open loop: "
                         f"{o['before'][axis]:.4f} before, {o['after'][axis]:.4f} after, "
                         f"the flown aircraft itself {o['floor'][axis]:.4f}")
    for name, g in result["derivative_gap"].items():
        lines.append(f"held-out {name}: RMS error {g['model']:.4g} before, {g['updated']:.4g} "
                     "after")
    return lines


def _curve(campaign: Campaign, df: pd.DataFrame, folder: Path) -> pd.DataFrame:
    """The model curve, computed once per campaign folder (it depends on the card only)."""
    path = folder / CURVE
    if path.is_file():
        return pd.read_parquet(path)
    alphas = df.groupby("index")["alpha"].first().to_dict()
    curve = model_curve(campaign, alphas)
    curve.to_parquet(path, index=False)
    return curve
