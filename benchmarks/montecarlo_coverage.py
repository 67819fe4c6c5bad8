"""Coverage of the 95 % intervals by method on one card (docs/montecarlo.md, "Coverage").

Runs (or continues: the studies live in --study-root and are resumed) a Monte Carlo study
of ``--n`` realizations per method on the card, and writes, per method and derivative,
the bias, scatter, mean bound, scatter/bound and coverage, and whether the derivative is
well excited (scatter/bound < 3, the issue's definition) and inside the 85-99 % band, to
benchmarks/results/montecarlo_coverage.{md,json}.

    .venv/bin/python benchmarks/montecarlo_coverage.py --n 60 --methods ee fem oe
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

from flightid.scenarios import montecarlo

RESULTS = Path(__file__).resolve().parent / "results" / "montecarlo_coverage"
BAND = (0.85, 0.99)
WELL_EXCITED = 3.0  # scatter / bound below this


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=60)
    parser.add_argument("--card", default="navion-demo")
    parser.add_argument("--model", default="lat")
    parser.add_argument("--methods", nargs="+", default=["ee", "fem", "oe"])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--study-root", default="/tmp")
    args = parser.parse_args()
    doc: dict = {"card": args.card, "model": args.model, "n": args.n, "band": BAND,
                 "well_excited_ratio": WELL_EXCITED, "methods": {}}
    lines = [f"coverage of the 95 % intervals, {args.card}, {args.model}, n = {args.n} per "
             "method; in band: well excited (scatter/bound < 3) and coverage in 85-99 %", ""]
    for method in args.methods:
        folder = Path(args.study_root) / f"mc-{method}-{args.model}{args.n}"
        t0 = time.perf_counter()
        summary = montecarlo.run(args.card, args.n, method, args.model, study_dir=folder,
                                 workers=args.workers, report=False)
        wall = time.perf_counter() - t0
        rows = summary.as_dict()["rows"]
        well = [r for r in rows if r["ratio"] is not None and r["ratio"] < WELL_EXCITED]
        inside = [r["name"] for r in well if BAND[0] <= r["coverage"] <= BAND[1]]
        doc["methods"][method] = {"summary": summary.as_dict(), "wall_s": wall,
                                  "well_excited": [r["name"] for r in well],
                                  "in_band": inside}
        lines += [f"{method}: {summary.realizations} realizations, {summary.failures} failed; "
                  f"{len(inside)} of {len(well)} well-excited derivatives in the band", "",
                  "| derivative | truth | bias | scatter | mean bound | scatter/bound | "
                  "coverage |", "|---|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['name']} | {r['truth']:+.4f} | {r['bias']:+.5f} | "
                         f"{r['scatter']:.5f} | {r['mean_bound']:.5f} | {r['ratio']:.2f} | "
                         f"{100 * r['coverage']:.0f} % |")
        lines.append("")
    doc["machine"] = {"cpus": os.cpu_count(), "python": platform.python_version(),
                      "load_average_end": os.getloadavg()}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.with_suffix(".json").write_text(json.dumps(doc, indent=1) + "\n")
    RESULTS.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
