"""Scaling of the Monte Carlo study (``flightid.scenarios.montecarlo.run``) on this machine.

Measures, in one run:

1. a bare loop, in this process, of ``fly_card`` + ``identify`` + ``score`` over the
   first K realizations of the study (``--k``, default all n) (the same seeds, one BLAS thread as in
   a study worker): seconds per realization;
2. the study with ``workers=1`` on the same K realizations: wall time, and its
   throughput against the bare loop (target >= 80 %);
3. the study with ``workers=2`` on the same K: speed-up over ``workers=1`` (target
   >= 1.8x on 2 cores);
   Beside it, the machine's own ceiling: two bare loops of K/2 at once in two processes
   (a 2-vCPU virtual machine whose vCPUs share a core cannot reach 2x);
4. the full n-realization study with ``workers=2`` (the study of (3) when K = n): wall
   time, failures, and per derivative the coverage of the 95 % intervals and the
   scatter/bound ratio.

Every study runs in a fresh temporary folder and its wall time includes everything that
``run`` does (starting the worker processes, writing the Parquet rows, the summary and
report.html). Writes benchmarks/results/montecarlo_scaling.txt and .json.

    .venv/bin/python benchmarks/montecarlo_scaling.py [--n 200] [--card navion-demo]
        [--method oe] [--model lat]
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import multiprocessing
import os
import platform
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from importlib import metadata
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from flightid.identification.evaluation.scoring import record_truth, score
from flightid.identification.identify import identify
from flightid.scenarios import montecarlo
from flightid.scenarios.cards import fly_card, load_card
from flightid.scenarios.montecarlo.study import REALIZATION_ERRORS, Study

RESULTS = Path(__file__).resolve().parent / "results" / "montecarlo_scaling.txt"
TARGET_SPEEDUP = 1.8
TARGET_THROUGHPUT = 0.80
COVERAGE_BAND = (0.85, 0.99)


def machine() -> dict[str, Any]:
    """nproc, CPU model, load, python and package versions."""
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for pkg in ("flightid", "jsbsim", "numpy", "scipy", "pandas", "pyarrow", "dask"):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "absent"
    affinity = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return {"nproc": affinity or os.cpu_count(), "cpu_count": os.cpu_count(), "cpu": cpu,
            "machine": platform.machine(), "python": platform.python_version(),
            "versions": versions, "load_before": list(os.getloadavg())}


def bare_loop(description: Study, k: int, first: int = 0) -> dict[str, Any]:
    """fly_card + identify + score of realizations first..first+k-1 in this process."""
    card = load_card(description.card)
    failures = 0
    t0 = time.perf_counter()
    c0 = time.process_time()
    with threadpool_limits(1):
        for i in range(first, first + k):
            seed = description.realization_seed(i, card)
            try:
                measured, truth_record = fly_card(card, seed)
                est = identify(measured, description.method, description.model,
                               **dict(description.options))
            except REALIZATION_ERRORS:
                failures += 1
                continue
            if est.fit.get("converged") is False:
                failures += 1
                continue
            score(est, record_truth(truth_record))
    wall = time.perf_counter() - t0
    return {"k": k, "wall_s": wall, "cpu_s": time.process_time() - c0,
            "s_per_realization": wall / k, "failures": failures}


def parallel_bare(description: Study, k: int) -> dict[str, Any]:
    """The machine's own ceiling: two bare loops at once in two processes, each over half
    of the K realizations, each timed inside its process (no start-up, no study)."""
    half = k // 2
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(2, mp_context=context) as pool:
        pool.submit(math.sqrt, 1.0).result()  # both workers started before timing
        pool.submit(math.sqrt, 1.0).result()
        runs = list(pool.map(bare_loop, [description] * 2, [half, k - half], [0, half]))
    return {"halves": runs, "slowest_s": max(r["wall_s"] for r in runs)}


def study(args: argparse.Namespace, n: int, workers: int) -> tuple[dict[str, Any], Any]:
    """The study of n realizations with ``workers`` local processes, fresh folder."""
    with tempfile.TemporaryDirectory(prefix="mc-scaling-") as tmp:
        t0 = time.perf_counter()
        summary = montecarlo.run(args.card, n, method=args.method, model=args.model,
                                 study_dir=Path(tmp) / "study", workers=workers)
        wall = time.perf_counter() - t0
        t1 = time.perf_counter()
        montecarlo.rebuild_report(Path(tmp) / "study")  # what the summary+report cost
        report_s = time.perf_counter() - t1
    return {"n": n, "workers": workers, "wall_s": wall, "s_per_realization": wall / n,
            "report_s": report_s,
            "realizations_per_s": n / wall, "failures": summary.failures,
            "failure_reasons": summary.failure_reasons}, summary


def pct(x: float) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:.0f} %"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=200)
    parser.add_argument("--card", default="navion-demo")
    parser.add_argument("--method", default="oe")
    parser.add_argument("--model", default="lat")
    parser.add_argument("--k", type=int, default=None,
                        help="realizations in the bare loop and the 1- and 2-worker studies "
                             "(default n)")
    parser.add_argument("--output", type=Path, default=RESULTS)
    args = parser.parse_args()
    k = min(args.n, args.k or args.n)
    info = machine()
    description = Study(args.card, args.n, args.method, args.model)

    def log(msg: str) -> None:
        print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)

    log(f"bare loop, K={k}")
    bare = bare_loop(description, k)
    log(f"  {bare['s_per_realization']:.3f} s per realization")
    log("two bare loops at once, K/2 each")
    ceiling = parallel_bare(description, k)
    log(f"  slowest {ceiling['slowest_s']:.1f} s")
    log("study workers=1, n=1 (fixed cost)")
    fixed, _ = study(args, 1, 1)
    log(f"  {fixed['wall_s']:.1f} s")
    log(f"study workers=1, K={k}")
    one, _ = study(args, k, 1)
    log(f"  {one['wall_s']:.1f} s")
    log(f"study workers=2, K={k}")
    two, two_summary = study(args, k, 2)
    log(f"  {two['wall_s']:.1f} s")
    if k < args.n:
        log(f"study workers=2, n={args.n}")
        full, summary = study(args, args.n, 2)
        log(f"  {full['wall_s']:.1f} s")
    else:
        full, summary = two, two_summary
    info["load_after"] = list(os.getloadavg())

    throughput = bare["wall_s"] / one["wall_s"]  # study rate / bare rate
    speedup = one["wall_s"] / two["wall_s"]
    marginal = ("n/a (n = K)" if args.n <= k else
                f"{(full['wall_s'] - two['wall_s']) / (args.n - k):.3f} s per realization")
    m1 = (one["wall_s"] - fixed["wall_s"]) / (k - 1) if k > 1 else math.nan
    marginal1 = f"{m1:.3f} s per realization" if k > 1 else "n/a (K = 1)"
    steady = f"{100 * bare['s_per_realization'] / m1:.1f} %" if k > 1 else "n/a"
    machine_ceiling = bare["wall_s"] / ceiling["slowest_s"]
    speedup_marginal = ((one["wall_s"] - fixed["wall_s"]) / (two["wall_s"] - fixed["wall_s"])
                        if two["wall_s"] > fixed["wall_s"] else math.nan)
    rows = summary.as_dict()["rows"]
    covs = [r["coverage"] for r in rows if r["coverage"] is not None]

    lines = [
        f"Monte Carlo study scaling: card {args.card}, method {args.method}, model "
        f"{args.model}; K={k}, n={args.n}",
        f"measured {datetime.datetime.now().isoformat(timespec='seconds')}; "
        f"nproc {info['nproc']}, {info['cpu']} ({info['machine']}); python "
        f"{info['python']}; " + ", ".join(f"{p} {v}" for p, v in info["versions"].items()),
        "load average before {:.2f} {:.2f} {:.2f}, after {:.2f} {:.2f} {:.2f}".format(
            *info["load_before"], *info["load_after"]),
        "",
        "wall time                                           total s  s/realization  "
        "realizations/s",
        f"(1) bare loop fly_card+identify+score, K={k:<4}        {bare['wall_s']:7.1f}  "
        f"{bare['s_per_realization']:13.3f}  {k / bare['wall_s']:14.3f}",
        f"(2) study, workers=1, K={k:<4}                        {one['wall_s']:7.1f}  "
        f"{one['s_per_realization']:13.3f}  {one['realizations_per_s']:14.3f}",
        f"(3) study, workers=2, K={k:<4}                        {two['wall_s']:7.1f}  "
        f"{two['s_per_realization']:13.3f}  {two['realizations_per_s']:14.3f}",
        f"(4) study, workers=2, n={args.n:<4}                        {full['wall_s']:7.1f}  "
        f"{full['s_per_realization']:13.3f}  {full['realizations_per_s']:14.3f}",
        "",
        f"bare loop CPU time {bare['cpu_s']:.1f} s ({bare['failures']} failed realizations)",
        f"fixed cost of a study (n=1, workers=1: start the worker, write the rows, summary "
        f"and report.html): {fixed['wall_s']:.1f} s wall, of which about "
        f"{bare['s_per_realization']:.1f} s is the one realization",
        f"of which load + summary + report.html (timed again afterwards): "
        f"{fixed['report_s']:.1f} s at n=1, {one['report_s']:.1f} s at n={k}, "
        f"{full['report_s']:.1f} s at n={args.n}",
        f"marginal cost with workers=1 ((2) - fixed) / (K - 1): {marginal1}; "
        f"steady-state throughput / bare loop: {steady}",
        f"marginal cost with workers=2 ((4) - (3)) / (n - K): {marginal}",
        f"study workers=1 throughput / bare loop: {100 * throughput:.1f} % "
        f"(target >= {100 * TARGET_THROUGHPUT:.0f} %: "
        f"{'met' if throughput >= TARGET_THROUGHPUT else 'NOT met'})",
        f"speed-up workers=2 over workers=1: {speedup:.2f}x "
        f"(target >= {TARGET_SPEEDUP}x: {'met' if speedup >= TARGET_SPEEDUP else 'NOT met'}); "
        f"without the fixed cost ((2) - fixed) / ((3) - fixed): {speedup_marginal:.2f}x",
        f"the machine's own ceiling, two bare loops of K/2 at once in two processes: "
        f"slowest {ceiling['slowest_s']:.1f} s against {bare['wall_s']:.1f} s for K in one, "
        f"{machine_ceiling:.2f}x",
        f"n={args.n} study: {full['wall_s']:.1f} s wall, {summary.realizations} realizations, "
        f"{full['failures']} failures {full['failure_reasons'] or ''}".rstrip(),
        "",
        "derivative        truth       bias    scatter  mean bound  scatter/bound  "
        "coverage 95 %",
    ]
    for r in rows:
        def f(v: Any, fmt: str) -> str:
            return format(v, fmt) if v is not None else "nan"
        lines.append(
            f"{r['name']:<12} {f(r['truth'], '+10.4f')} {f(r['bias'], '+10.4f')} "
            f"{f(r['scatter'], '10.4f')} {f(r['mean_bound'], '11.4f')} "
            f"{f(r['ratio'], '14.2f')} {pct(r['coverage']):>14}")
    if covs:
        inside = sum(COVERAGE_BAND[0] <= c <= COVERAGE_BAND[1] for c in covs)
        lines += ["", f"coverage range {pct(min(covs))} - {pct(max(covs))}; "
                      f"{inside} of {len(covs)} derivatives within "
                      f"{pct(COVERAGE_BAND[0])} - {pct(COVERAGE_BAND[1])}"]
    text = "\n".join(lines) + "\n"
    print(text)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text)
    payload = {"args": vars(args) | {"output": str(args.output)}, "k": k, "machine": info,
               "bare": bare, "study_n1_workers1": fixed, "study_workers1": one,
               "study_workers2": two, "study_full": full,
               "throughput_vs_bare": throughput, "speedup_2_over_1": speedup,
               "speedup_without_fixed": speedup_marginal, "parallel_bare": ceiling,
               "machine_ceiling": machine_ceiling, "marginal_workers1_s": m1,
               "summary": summary.as_dict()}
    args.output.with_suffix(".json").write_text(json.dumps(payload, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
