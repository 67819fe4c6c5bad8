"""Input-design comparison on the Navion, longitudinal, output error (docs/montecarlo.md):
doublet, 2-1-1, 3211, sweep and multisine at equal amplitude (or ``--equal energy``), the
same seeds for every design; writes benchmarks/results/design_compare-<equal>.{json,md,png,html}.

    .venv/bin/python benchmarks/design_compare.py --n 50 --equal amplitude --workers 2

The studies live in --study (default: flightid-design-compare-<equal> in the system's
temporary folder) and continue when the script is rerun (a larger --n extends them).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

from flightid.scenarios.montecarlo.design import experiment
from flightid.scenarios.montecarlo.design import report as design_report
from flightid.scenarios.montecarlo.design.comparison import compare

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50)
    parser.add_argument("--card", default="navion-demo")
    parser.add_argument("--method", default="oe")
    parser.add_argument("--model", default="lon")
    parser.add_argument("--equal", default="amplitude", choices=experiment.EQUAL)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--study", default=None)
    args = parser.parse_args()
    study = Path(args.study or
                 Path(tempfile.gettempdir()) / f"flightid-design-compare-{args.equal}")
    t0 = time.perf_counter()
    comparison = compare(args.card, args.n, args.method, args.model, study,
                         equal=args.equal, workers=args.workers)
    wall = time.perf_counter() - t0
    stem = f"design_compare-{args.equal}"
    RESULTS.mkdir(exist_ok=True)
    png, page = design_report.write(comparison, study)
    (RESULTS / f"{stem}.png").write_bytes(png.read_bytes())
    (RESULTS / f"{stem}.html").write_text(page.read_text())
    doc = comparison.as_dict()
    doc["wall_s"] = wall
    doc["machine"] = {"cpus": os.cpu_count(), "python": platform.python_version(),
                      "load_average": os.getloadavg()}
    (RESULTS / f"{stem}.json").write_text(json.dumps(doc, indent=2, default=str) + "\n")
    text = design_report.markdown(comparison)
    (RESULTS / f"{stem}.md").write_text(text)
    print(text)
    print(f"wall {wall:.1f} s; wrote {RESULTS / stem}.*")


if __name__ == "__main__":
    main()
