"""Run time of one full gap diagnosis (target: <= 30 s on one core): a 60 s record of the
twinotter exciting both axes (aileron and rudder doublets and a 2-1-1, then an elevator
doublet and 3211; research sensors corrected to the CG, light turbulence) flown with a
Cn_beta error, diagnosed against the plain twinotter with ``diagnose``'s defaults: both
axes, each tested against the null level; where there is a gap, every candidate of the
catalogue screened (a few Gauss-Newton steps), the leading ones fitted to convergence and
checked on held-out windows, pairs, and the sequence until the null level. The JSBSim
refit (``refine=True``) is not included: it adds 10-27 s (docs/gap.md).

One BLAS thread and the process pinned to one CPU. Both the wall time and the process CPU
time are written: on a machine others are using the wall time is inflated, the CPU time
much less so (re-measure the wall time on a quiet machine).
Writes benchmarks/results/gap_diagnosis_time.json and .txt.

    .venv/bin/python benchmarks/gap_diagnosis_time.py [--repeat 2]
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

from flightid.identification.gap import diagnose
from flightid.scenarios.cards import card_from_dict, fly_card

RESULTS = Path(__file__).parent / "results"
TARGET_S = 30.0
CARD = {
    "name": "gap-timing-twinotter", "aircraft": "twinotter", "duration": 60.0, "rate": 50.0,
    "seed": 7, "condition": {"altitude": 1890.0, "speed": 72.2},
    "maneuver": [
        {"kind": "doublet", "surface": "da", "start": 2.0, "base": 1.0, "amplitude_deg": 6.0},
        {"kind": "211", "surface": "dr", "start": 12.0, "base": 1.0, "amplitude_deg": 2.8},
        {"kind": "doublet", "surface": "da", "start": 22.0, "base": 1.0, "amplitude_deg": -6.0},
        {"kind": "doublet", "surface": "dr", "start": 32.0, "base": 1.0, "amplitude_deg": 2.8},
        {"kind": "doublet", "surface": "de", "start": 42.0, "base": 1.0, "amplitude_deg": 2.0},
        {"kind": "3211", "surface": "de", "start": 50.0, "base": 0.5, "amplitude_deg": 2.0},
    ],
    "sensors": {"suite": "research", "drop": ["vanes", "lever_arm"]},
    "disturbance": [{"kind": "turbulence", "intensity": "light"}],
    "effect": [{"name": "derivative_delta", "derivative": "Cn_beta", "axes": "body",
                "delta": -0.04}],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    record, _ = fly_card(card_from_dict(CARD, "<gap timing>"))
    runs = []
    with threadpool_limits(1):
        for _ in range(args.repeat):
            w0, c0 = time.perf_counter(), time.process_time()
            result = diagnose([record], "twinotter")
            runs.append({"wall_s": time.perf_counter() - w0, "cpu_s": time.process_time() - c0})
    best = min(runs, key=lambda r: r["wall_s"])
    out = {"date": f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC",
           "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
           "load_average": os.getloadavg(), "record_s": float(record.time[-1]),
           "windows": result.windows,
           "verdicts": {a: g.verdict for a, g in result.axes().items()},
           "named": [r.candidate.label for r in result.named_all()],
           "candidates": len(result.effects), "pairs": len(result.pairs), "runs": runs,
           "best_wall_s": best["wall_s"], "best_cpu_s": min(r["cpu_s"] for r in runs),
           "target_s": TARGET_S}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "gap_diagnosis_time.json").write_text(json.dumps(out, indent=2))
    text = (f"gap diagnosis of one {out['record_s']:.0f} s record (twinotter, both axes: "
            + ", ".join(f"{a} {v}" for a, v in out["verdicts"].items()) + "; "
            f"{len(result.windows['fit'])} windows, {out['candidates']} candidates, "
            f"{out['pairs']} pairs, named {' then '.join(out['named']) or 'nothing'}), one "
            f"core, {out['date']}, load average {out['load_average'][0]:.1f} on "
            f"{out['cpus']} CPUs:\n"
            + "".join(f"  run {k + 1}: wall {r['wall_s']:.1f} s, CPU {r['cpu_s']:.1f} s\n"
                      for k, r in enumerate(runs))
            + f"best wall {out['best_wall_s']:.1f} s, best CPU {out['best_cpu_s']:.1f} s "
              f"(target < {TARGET_S:.0f} s)\n")
    (RESULTS / "gap_diagnosis_time.txt").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
