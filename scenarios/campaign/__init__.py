"""Flight-test campaigns: a matrix of test points flown with one flight card's maneuvers,
every point identified, the estimates set against the model's tables across the envelope.

    from flightid.scenarios import campaign
    result = campaign.run("twinotter-envelope", "campaigns/twinotter")

Modules: ``card`` (the campaign card), ``point`` (fly, reduce, identify, score one point),
``curve`` (the model's derivatives between the points), ``report`` (DIR/report.html).
The points run on the Monte Carlo executors (local processes or Dask) and are stored as
the Monte Carlo store stores realizations (one Parquet file per point, atomically), so a
rerun continues. docs/campaign.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from flightid.scenarios.campaign.card import Campaign, TestPoint, load_campaign, point_card
from flightid.scenarios.campaign.curve import model_curve
from flightid.scenarios.campaign.point import run_point
from flightid.scenarios.campaign.report import PointScore, point_scores, write_report
from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.executors import dask_client, run_dask, run_local

ESTIMATES = "estimates.parquet"
CURVE = "model_curve.parquet"

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


def run(card: str | Path | Campaign, output: str | Path, workers: int | None = None,
        dask_address: str | None = None, dask_scheduler_file: str | None = None,
        progress: Callable[[int, int], None] | None = None) -> CampaignResult:
    """Fly and identify every test point of ``card`` not yet stored in ``output``, then
    write OUTPUT/estimates.parquet (one row per point and derivative), OUTPUT/
    model_curve.parquet and OUTPUT/report.html. ``workers`` local processes (default one
    per CPU) or a Dask scheduler; ``progress(done, total)`` after each point. A folder
    holding another campaign is refused (``store.StudyMismatch``)."""
    campaign = card if isinstance(card, Campaign) else load_campaign(card)
    folder = Path(output)

    def keep(index: int, rows: list[dict]) -> None:
        store.write_realization(folder, index, rows)

    if dask_address is not None or dask_scheduler_file is not None:
        with dask_client(dask_address, dask_scheduler_file) as client:
            store.open_study(folder, campaign)  # type: ignore[arg-type]
            todo = sorted(set(range(campaign.n)) - store.done(folder))
            run_dask(campaign, todo, keep, client, progress, task=run_point,
                     key=f"flightid-campaign-{campaign.identity()['card_sha256'][:12]}")
    else:
        store.open_study(folder, campaign)  # type: ignore[arg-type]
        todo = sorted(set(range(campaign.n)) - store.done(folder))
        run_local(campaign, todo, keep, workers, progress, task=run_point)
    df = store.load(folder)
    df = df[df["index"] < campaign.n].reset_index(drop=True)
    df.to_parquet(folder / ESTIMATES, index=False)
    curve = _curve(campaign, df, folder)
    report = write_report(folder, campaign, df, curve)
    return CampaignResult(folder, campaign, df, curve, point_scores(df), report)


def _curve(campaign: Campaign, df: pd.DataFrame, folder: Path) -> pd.DataFrame:
    """The model curve, computed once per campaign folder (it depends on the card only)."""
    path = folder / CURVE
    if path.is_file():
        return pd.read_parquet(path)
    alphas = df.groupby("index")["alpha"].first().to_dict()
    curve = model_curve(campaign, alphas)
    curve.to_parquet(path, index=False)
    return curve
