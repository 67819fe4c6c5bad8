"""The blind check of many cases: draw, run each (``run.run_case``), write each result as it
finishes (``cases.jsonl`` under the output folder) and summarise (``summary.json``)."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flightid.scenarios.gap_benchmark.cases import Case, draw
from flightid.scenarios.gap_benchmark.run import CaseResult, run_case, summary, truths
from flightid.sim.flight import DepartureError

CASES_FILE = "cases.jsonl"
SUMMARY_FILE = "summary.json"
# what a case may fail with (its flight departs, its trim fails, a fit is singular): the
# case is reported with its error and counts as missed, the study goes on
CASE_ERRORS = (DepartureError, RuntimeError, ValueError, ArithmeticError, KeyError)

Progress = Callable[[int, int, str], None]  # (done, total, label of the case just done)


@dataclass
class Benchmark:
    """The blind check's cases and their summary."""

    n: int
    seed: int
    results: list[CaseResult]

    def summary(self) -> dict[str, Any]:
        return summary(self.results)

    def to_json(self) -> dict[str, Any]:
        """The summary's fractions (``top1``, ``top3``, ``shrinkage``,
        ``unexplained_correct``, ...), ``n``, ``seed`` and the ``cases``."""
        return {"n": self.n, "seed": self.seed, **self.summary(),
                "cases": [r.to_json() for r in self.results]}


def failed(case: Case, error: BaseException) -> CaseResult:
    """A case that could not be flown or diagnosed: missed, with its error."""
    nan = math.nan
    return CaseResult(case, [], [], False, False, False, nan, nan, nan, nan,
                      error=f"{type(error).__name__}: {error}")


def benchmark(n: int, seed: int, output: str | Path | None = None,
              progress: Progress | None = None) -> Benchmark:
    """``n`` blind cases drawn from ``seed``, each flown, diagnosed and scored; with
    ``output``, each case is appended to ``output/cases.jsonl`` as it finishes and the
    summary written to ``output/summary.json``."""
    if n < 1:
        raise ValueError(f"gap-benchmark: --n must be at least 1, got {n}")
    folder = Path(output) if output is not None else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / CASES_FILE).write_text("")
    cases = draw(n, seed, truths())
    results: list[CaseResult] = []
    for k, case in enumerate(cases):
        try:
            result = run_case(case)
        except CASE_ERRORS as exc:
            result = failed(case, exc)
        results.append(result)
        if folder is not None:
            with open(folder / CASES_FILE, "a") as f:
                f.write(json.dumps(result.to_json()) + "\n")
        if progress is not None:
            progress(k + 1, n, case.label)
    bench = Benchmark(n, seed, results)
    if folder is not None:
        (folder / SUMMARY_FILE).write_text(json.dumps(bench.to_json(), indent=2))
    return bench
