"""Monte Carlo accuracy studies: fly a card many times, identify every flight, and measure
bias, scatter and the coverage of the reported bounds; locally or on a Dask cluster.

    from flightid.scenarios import montecarlo
    summary = montecarlo.run("navion-demo", 100, method="oe", model="lat",
                             study_dir="studies/navion-oe-lat")

Modules: ``study`` (the description, one realization), ``store`` (STUDY/study.json and
one Parquet file per realization; continuing), ``executors`` (local processes, Dask),
``summary`` (per-derivative statistics), ``report`` (STUDY/report.html); input-design
comparisons in ``design/``. docs/montecarlo.md.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from flightid.scenarios.montecarlo import store
from flightid.scenarios.montecarlo.disperse import parse_all
from flightid.scenarios.montecarlo.executors import dask_client, run_dask, run_local
from flightid.scenarios.montecarlo.report import write_report
from flightid.scenarios.montecarlo.store import SUMMARY_COLUMNS, StudyMismatch, done, load
from flightid.scenarios.montecarlo.study import Study, dry_run, run_realization
from flightid.scenarios.montecarlo.summary import Summary, summarize

__all__ = ["Study", "StudyMismatch", "Summary", "done", "dry_run", "load", "rebuild_report",
           "run", "run_realization", "summarize"]


def run(card: str | Path, n: int, method: str = "oe", model: str = "lat",
        options: Mapping[str, Any] | None = None, study_dir: str | Path | None = None,
        workers: int | None = None, dask_address: str | None = None,
        progress: Callable[[int, int], None] | None = None, *, seed: int | None = None,
        dask_scheduler_file: str | Path | None = None, report: bool = True,
        disperse: Sequence[str] = (), raw: bool = False) -> Summary:
    """Run (or continue, or extend) a Monte Carlo study of one card.

    Each flight is identified as ``flightid identify`` does: the standard data reduction
    (accelerometers and vanes to the CG, vane scale and bias;
    ``reduction.standard_reduction``) unless ``raw``, then ``identify``. Realizations
    already stored are not recomputed; a stored study described otherwise (card, method,
    model, options, seed, dispersions, data reduction) is refused (StudyMismatch).

    Parameters
    ----------
    card : str or Path
        A library card name or a card file.
    n : int
        The number of realizations.
    method, model : str
        The identification method's id and its model.
    options : mapping, optional
        The method's options.
    study_dir : str or Path, optional
        Where the study is stored (default ``montecarlo/<card>-<method>-<model>``).
    workers : int, optional
        Local processes (default: one per CPU).
    dask_address : str, optional
        A Dask scheduler's address (instead of local processes).
    progress : callable, optional
        ``progress(done, total)`` after each realization.
    seed : int, optional
        The study's seed (default: the card's).
    dask_scheduler_file : str or Path, optional
        A Dask scheduler file (instead of ``dask_address``).
    report : bool
        Write the HTML report and the histograms into ``study_dir``.
    disperse : sequence of str
        Dispersion specs such as ``mass_scale:0.05`` (``disperse.parse``), drawn anew for
        each realization; their values are stored in its rows and its truth is the
        dispersed aircraft's.
    raw : bool
        Identify each record as flown, without the standard data reduction (as
        ``flightid identify --raw``).

    Returns
    -------
    Summary
        Per derivative: bias, scatter, mean bound, coverage (derivative units, per rad).
    """
    dispersions = parse_all(disperse)  # a bad spec fails here, not once per realization
    description = Study(str(card), int(n), method, model, dict(options or {}), seed,
                        tuple(d.text() for d in dispersions), bool(raw))
    loaded = dry_run(description)  # method, model, options, seed, trim: before any write
    folder = Path(study_dir) if study_dir is not None else \
        Path("montecarlo") / f"{loaded.name}-{method}-{model}"

    def keep(index: int, rows: list[dict[str, Any]]) -> None:
        store.write_realization(folder, index, rows)

    if dask_address is not None or dask_scheduler_file is not None:
        with dask_client(dask_address, None if dask_scheduler_file is None
                         else str(dask_scheduler_file)) as client:  # fails fast, unwritten
            store.open_study(folder, description)
            run_dask(description, sorted(set(range(int(n))) - done(folder)), keep, client,
                     progress)
    else:
        store.open_study(folder, description)
        todo = sorted(set(range(int(n))) - done(folder))
        run_local(description, todo, keep, workers, progress, store_in=folder)  # workers store
    df = load(folder, SUMMARY_COLUMNS)
    df = df[df["index"] < int(n)]
    summary = summarize(df)
    if report:
        write_report(folder, df, summary, _title(description))
    return summary


def _title(description: Study | dict[str, Any]) -> str:
    d = description.as_dict() if isinstance(description, Study) else description
    return f"Monte Carlo: {d['card']}, {d['method']} {d['model']}, n={d['n']}"


def rebuild_report(study_dir: str | Path) -> tuple[Path, Summary]:
    """Rebuild STUDY/report.html from the stored rows (all of them).

    Parameters
    ----------
    study_dir : str or Path
        The study folder STUDY.

    Returns
    -------
    tuple[Path, Summary]
        The report's path and the summary.
    """
    stored = store.read_description(study_dir)
    df = load(study_dir, SUMMARY_COLUMNS)
    summary = summarize(df)
    return write_report(study_dir, df, summary, _title(stored["description"])), summary
