"""The blind check of many cases on the Monte Carlo executors (local processes or a Dask
cluster), resumable: each finished case is appended to ``OUTPUT/cases.jsonl`` (one JSON
line, written whole), the study's identity is in ``OUTPUT/study.json``, and a rerun with
the same output folder runs only the cases not stored yet (a larger n or more nulls
extend it; another seed, turbulence, aircraft set or diagnosis options are refused)."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flightid.files import check_writable
from flightid.scenarios.gap_benchmark.cases import (
    AIRCRAFT,
    NULL_INDEX,
    TURBULENCE,
    Case,
    draw,
    fingerprint,
)
from flightid.scenarios.gap_benchmark.run import run_case, truths
from flightid.scenarios.gap_benchmark.scoring import CaseResult
from flightid.scenarios.gap_benchmark.summary import summary
from flightid.scenarios.montecarlo.executors import dask_client, run_dask, run_local
from flightid.sim.flight.simulation import DepartureError
from flightid.sim.jsbsim.trim import TrimError

CASES_FILE = "cases.jsonl"
STUDY_FILE = "study.json"
SUMMARY_FILE = "summary.json"
# what a case may fail with (its flight departs, its trim fails, a fit is singular): the
# case is reported with its error and counts as missed, the study goes on
CASE_ERRORS = (DepartureError, TrimError, RuntimeError, ValueError, ArithmeticError,
               KeyError)

Progress = Callable[[int, int], None]  # (done, total)


@dataclass(frozen=True)
class Plan:
    """What a worker needs: the drawn cases by index, the truths they were drawn from,
    the turbulence and the diagnosis options."""

    cases: dict[int, Case]
    truths: dict[str, dict[str, float]]
    turbulence: str = "light"
    options: dict[str, Any] = field(default_factory=dict)


def run_index(plan: Plan, index: int) -> list[dict[str, Any]]:
    """One case of ``plan`` run and scored, as one JSON-able row (a failed case with its
    error): the task the executors give each worker.

    Parameters
    ----------
    plan : Plan
        The study's plan.
    index : int
        Case index in ``plan.cases``.

    Returns
    -------
    list[dict[str, Any]]
        One row.
    """
    case = plan.cases[index]
    try:
        result = run_case(case, plan.turbulence, plan.truths.get(case.aircraft),
                          **plan.options)
    except CASE_ERRORS as exc:
        result = CaseResult(case, error=f"{type(exc).__name__}: {exc}")
    return [result.to_json()]


@dataclass
class Benchmark:
    """The blind check's results and their summary."""

    n: int
    seed: int
    nulls: int
    turbulence: str
    results: list[CaseResult]

    def summary(self) -> dict[str, Any]:
        return summary(self.results)

    def to_json(self) -> dict[str, Any]:
        """The summary's figures, ``by_kind``, the study's description and the ``cases``."""
        return _plain({"n": self.n, "seed": self.seed, "nulls": self.nulls,
                       "turbulence": self.turbulence, **self.summary(),
                       "cases": [r.to_json() for r in self.results]})


def check(n: int, seed: int, nulls: int, turbulence: str, aircraft: tuple[str, ...],
          output: str | Path | None, workers: int | None) -> None:
    """Raise ValueError (or the OSError of an unwritable output) naming the option, before
    anything is flown.

    Parameters
    ----------
    n : int
        Number of drawn cases, >= 1.
    seed : int
        Study seed, >= 0.
    nulls : int
        Number of null cases, >= 0.
    turbulence : str
        Turbulence intensity, one of ``TURBULENCE``.
    aircraft : tuple[str, ...]
        Aircraft to draw from, keys of ``AIRCRAFT``.
    output : str or Path or None
        Output folder, or None.
    workers : int or None
        Worker processes, or None.
    """
    if isinstance(n, bool) or int(n) < 1:
        raise ValueError(f"--n must be at least 1, got {n}")
    if int(seed) < 0:
        raise ValueError(f"--seed must be 0 or more, got {seed}")
    if int(nulls) < 0:
        raise ValueError(f"--nulls must be 0 or more, got {nulls}")
    if turbulence not in TURBULENCE:
        raise ValueError(f"--turbulence must be one of {', '.join(TURBULENCE)}, "
                         f"got {turbulence!r}")
    unknown = [a for a in aircraft if a not in AIRCRAFT]
    if unknown or not aircraft:
        raise ValueError(f"--aircraft {', '.join(unknown) or '(none)'} is not "
                         f"among {', '.join(AIRCRAFT)}")
    if workers is not None and int(workers) < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    if output is not None:
        folder = Path(output)
        if folder.exists() and not folder.is_dir():
            raise ValueError(f"--output {folder} is a file, not a folder")
        inside = folder / CASES_FILE
        while not inside.parent.exists() and inside.parent != inside.parent.parent:
            inside = inside.parent
        try:
            check_writable(inside)  # a temporary file made and removed: nothing written
        except OSError as exc:
            raise ValueError(f"--output {folder}: {exc}") from None


def identity(seed: int, turbulence: str, aircraft: tuple[str, ...],
             options: dict[str, Any]) -> dict[str, Any]:
    """What makes two runs the same study (n and nulls may grow): the seed, turbulence,
    aircraft, diagnosis options and the draw's ``fingerprint``.

    Parameters
    ----------
    seed : int
        Study seed.
    turbulence : str
        Turbulence intensity.
    aircraft : tuple[str, ...]
        Aircraft drawn from.
    options : dict[str, Any]
        Diagnosis options.

    Returns
    -------
    dict[str, Any]
        The identity, JSON-able.
    """
    return {"seed": int(seed), "turbulence": turbulence, "aircraft": list(aircraft),
            "options": {k: options[k] for k in sorted(options)}, "draw": fingerprint()}


def _open(folder: Path, ident: dict[str, Any]) -> dict[int, CaseResult]:
    """The stored results of the study in ``folder`` (created when new); a folder holding
    another study is refused naming --output."""
    path = folder / STUDY_FILE
    if path.exists():
        stored = json.loads(path.read_text())
        if stored != ident:
            diffs = [f"{k}: stored {stored.get(k)!r}, asked {ident.get(k)!r}"
                     for k in sorted(set(stored) | set(ident)) if stored.get(k) != ident.get(k)]
            raise ValueError(f"--output {folder} holds another study "
                             f"({'; '.join(diffs)}); use another folder")
    else:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = folder / f".{STUDY_FILE}.{os.getpid()}.tmp"
        tmp.write_text(json.dumps(ident, indent=2) + "\n")
        os.replace(tmp, path)
    done: dict[int, CaseResult] = {}
    cases = folder / CASES_FILE
    if cases.exists():
        for line in cases.read_text().splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:  # a line cut by a crash: run that case again
                continue
            r = CaseResult.from_json(row)
            done[r.case.index] = r
    return done


def benchmark(n: int, seed: int, nulls: int = 100, turbulence: str = "light",
              output: str | Path | None = None, progress: Progress | None = None,
              workers: int | None = 1, dask_address: str | None = None,
              aircraft: tuple[str, ...] = tuple(AIRCRAFT),
              options: dict[str, Any] | None = None) -> Benchmark:
    """``n`` blind cases and ``nulls`` null cases drawn from ``seed``, each flown in
    ``turbulence``, diagnosed without being told what was injected, and scored.

    Parameters
    ----------
    n : int
        Blind cases (single effects, pairs and effects outside the catalogue).
    seed : int
        The draw's seed.
    nulls : int
        Null cases (nothing injected), drawn on their own stream.
    turbulence : str
        "calm", "light" or "moderate" (MIL-F-8785C Dryden).
    output : str, Path or None
        A folder: each case is appended to ``output/cases.jsonl`` as it finishes, cases
        stored there already are not run again, and the summary goes to
        ``output/summary.json``; None: nothing written.
    progress : callable or None
        ``progress(done, total)`` after each case.
    workers : int or None
        Local processes (1: in this process; None: one per core).
    dask_address : str or None
        A Dask scheduler's address to run the cases on instead.
    aircraft : tuple of str
        The aircraft drawn from (project names and stock JSBSim ones).
    options : dict or None
        Passed to ``diagnose`` (tests: fewer steps).

    Returns
    -------
    Benchmark
        The cases' results and their summary per kind of effect.
    """
    options = dict(options or {})
    aircraft = tuple(aircraft)
    check(n, seed, nulls, turbulence, aircraft, output, workers)
    folder = Path(output) if output is not None else None
    done = _open(folder, identity(seed, turbulence, aircraft, options)) if folder else {}
    t = truths(aircraft)
    cases = draw(n, seed, t, nulls, aircraft)
    plan = Plan({c.index: c for c in cases}, t, turbulence, options)
    todo = [c.index for c in cases if c.index not in done]
    results = dict(done)

    def keep(index: int, rows: list[dict[str, Any]]) -> None:
        results[index] = CaseResult.from_json(rows[0])
        if folder is not None:
            with open(folder / CASES_FILE, "a") as f:
                f.write(json.dumps(rows[0]) + "\n")
                f.flush()

    skipped = len(cases) - len(todo)

    def report(finished: int, total: int) -> None:
        if progress is not None:
            progress(skipped + finished, skipped + total)

    if dask_address is not None:
        with dask_client(dask_address) as client:
            run_dask(plan, todo, keep, client, report, task=run_index,
                     key=f"flightid-gap-benchmark-{seed}")
    elif workers == 1:
        report(0, len(todo))
        for k, index in enumerate(todo):
            keep(index, run_index(plan, index))
            report(k + 1, len(todo))
    else:
        run_local(plan, todo, keep, workers, report, task=run_index)
    bench = Benchmark(n, seed, nulls, turbulence,
                      [results[c.index] for c in cases if c.index in results])
    if folder is not None:
        tmp = folder / f".{SUMMARY_FILE}.{os.getpid()}.tmp"
        tmp.write_text(json.dumps(bench.to_json(), indent=2))
        os.replace(tmp, folder / SUMMARY_FILE)
    return bench


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


__all__ = ["NULL_INDEX", "Benchmark", "Plan", "benchmark", "check", "run_index"]
