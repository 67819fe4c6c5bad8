"""The blind check of the gap diagnosis (issue 25): N cases drawn across the navion, the
twinotter and the telemaster (an effect of the catalogue at a moderate magnitude, or one
outside it), flown, diagnosed without being told, and scored
(``flightid.scenarios.gap_benchmark``).

Targets: top-1 attribution >= 90 %, held-out gap shrink >= 70 % after the named effect,
effects outside the catalogue reported unexplained in >= 80 % of their cases.

Writes benchmarks/results/gap_benchmark.json (summary and cases), .txt (a table), and
benchmarks/results/gap_benchmark/cases.jsonl as each case finishes.

    .venv/bin/python benchmarks/gap_benchmark.py [--n 50] [--seed 0]
    .venv/bin/python benchmarks/gap_benchmark.py --from-cases   # re-summarise cases.jsonl
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import time
from pathlib import Path

from threadpoolctl import threadpool_limits

from flightid.scenarios.gap_benchmark import Benchmark, CaseResult, benchmark
from flightid.scenarios.gap_benchmark.study import CASES_FILE

RESULTS = Path(__file__).parent / "results"


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def text(bench: Benchmark, wall_s: float) -> str:
    """The result as a plain-text table and summary."""
    s = bench.summary()
    lines = [f"gap blind check: {bench.n} cases, seed {bench.seed}, "
             f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
             f"wall {wall_s:.0f} s (one BLAS thread)", ""]
    lines.append(f"{'#':>3} {'case (injected)':58} {'top1':>4} {'top3':>4} {'shrink':>7} "
                 f"{'excess':>7} {'mag.err':>7}  named")
    for r in bench.results:
        inside = r.case.in_catalogue
        named = r.error or ((", ".join(r.named) + (" (partly unexplained)" if r.partly else ""))
                           if r.named else "unexplained")
        lines.append(
            f"{r.case.index:>3} {r.case.label[:58]:58} "
            f"{('yes' if r.top1 else 'no') if inside else '':>4} "
            f"{('yes' if r.top3 else 'no') if inside else '':>4} "
            f"{'-' if r.shrink != r.shrink else f'{r.shrink:.0%}':>7} "
            f"{'-' if r.excess_shrink != r.excess_shrink else f'{r.excess_shrink:.0%}':>7} "
            f"{'-' if r.magnitude_error != r.magnitude_error else f'{r.magnitude_error:.0%}':>7}"
            f"  {named}")
    lines += ["",
              f"in the catalogue: {s['in_catalogue']} cases; top-1 {_pct(s['top1'])} "
              f"(target >= 90 %), top-3 {_pct(s['top3'])}",
              f"held-out shrink (median, correctly named): {_pct(s['shrinkage'])} (target >= "
              f"70 %); cases >= 70 %: {_pct(s['shrink_at_least_70'])}",
              f"shrink of the gap above the noise floor (median): {_pct(s['excess_shrinkage'])};"
              f" cases >= 70 %: {_pct(s['excess_shrink_at_least_70'])}",
              f"magnitude error (median, |estimate - injected| / |injected change|): "
              f"{_pct(s['magnitude_error_median'])}",
              f"in-catalogue cases reported unexplained: {_pct(s['false_unexplained'])}",
              f"not flown (departed, left out): {len(s['failed'])}"
              + "".join(f"\n  {f}" for f in s["failed"]),
              f"outside the catalogue: {s['outside']} cases; reported unexplained or partly "
              f"unexplained {_pct(s['unexplained_correct'])} (target >= 80 %)",
              "right attributions reported partly unexplained: "
              f"{_pct(s.get('false_partly_unexplained'))}",
              "by entry: " + ", ".join(f"{k} {v['top1']}/{v['cases']}"
                                       for k, v in s["by_entry"].items())]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--from-cases", action="store_true",
                        help="summarise the cases.jsonl of a run instead of running")
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    if args.from_cases:
        lines = (RESULTS / "gap_benchmark" / CASES_FILE).read_text().splitlines()
        results = [CaseResult.from_json(json.loads(x)) for x in lines if x.strip()]
        # a run stopped early: the cases it finished (n is what was finished)
        bench = Benchmark(len(results), args.seed, results)
        _write(bench, sum(r.seconds for r in results if r.seconds == r.seconds))
        return

    def progress(done: int, total: int, label: str) -> None:
        print(f"{done}/{total} {label}", flush=True)

    t0 = time.perf_counter()
    with threadpool_limits(1):
        bench = benchmark(args.n, args.seed, RESULTS / "gap_benchmark", progress)
    _write(bench, time.perf_counter() - t0)


def _write(bench: Benchmark, wall: float) -> None:
    (RESULTS / "gap_benchmark.json").write_text(
        json.dumps({"wall_s": wall, **bench.to_json()}, indent=2))
    out = text(bench, wall)
    (RESULTS / "gap_benchmark.txt").write_text(out)
    print(out)


if __name__ == "__main__":
    main()
