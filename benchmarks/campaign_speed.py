"""Wall time of a 20-point campaign (``flightid.scenarios.campaign.run``) on 2 cores.

The campaign flies the twinotter-id card's maneuvers (28 s each, research sensors) at 20
test points: altitude 1500 and 1900 m x airspeed 50, 55, 60, 65, 70 m/s x mass scale 1.0
and 1.1; every point is reduced and identified by output error (``--method``, default
oe6dof: 6-DOF output error, 24 derivatives; oe: the linear lateral model), in ``workers``
local processes, into a fresh folder. The wall time includes everything ``run`` does
(worker start-up, flights, trims, fits, Parquet rows, the model curve and the report).
The CPU seconds of the whole process tree (this process, the forkserver and the workers,
sampled every 0.2 s with psutil: a worker's last sample is taken at most 0.2 s before it
ends) are reported beside the wall time: on a machine shared with other jobs the wall
time measures the load as much as the campaign, the CPU seconds do not. Writes
benchmarks/results/campaign_speed-<method>.txt and .json.

    .venv/bin/python benchmarks/campaign_speed.py [--workers 2] [--method oe6dof]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import tempfile
import threading
import time
from pathlib import Path

import psutil

from flightid.scenarios import campaign
from flightid.scenarios.campaign.card import campaign_from_dict

RESULTS = Path(__file__).resolve().parent / "results"
TARGET_S = 300.0  # issue 35: a 20-point campaign with output error on 2 cores <= 5 min
MODELS = {"oe6dof": ("6dof", {"propulsive_moments": True}), "oe": ("lat", {})}


def card(method: str) -> dict:
    model, options = MODELS[method]
    return {"name": "bench-20", "card": "twinotter-id", "method": method, "model": model,
            "options": options, "seed": 1, "x": "speed",
            "matrix": {"altitude": [1500.0, 1900.0], "speed": [50.0, 55.0, 60.0, 65.0, 70.0],
                       "mass": [1.0, 1.1]}}


class TreeCpu:
    """CPU seconds (user + system) of this process and all its descendants, the ended ones
    included at their last sample."""

    def __init__(self, interval_s: float = 0.2) -> None:
        self.interval_s = interval_s
        self.seen: dict[tuple[int, float], float] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _sample(self) -> None:
        me = psutil.Process()
        for proc in [me, *me.children(recursive=True)]:
            try:
                t = proc.cpu_times()
                self.seen[(proc.pid, proc.create_time())] = t.user + t.system
            except psutil.Error:  # ended between the listing and the reading
                pass

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            self._sample()

    def __enter__(self) -> TreeCpu:
        self._sample()
        self.start = sum(self.seen.values())
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self._sample()
        self.seconds = sum(self.seen.values()) - self.start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--method", choices=sorted(MODELS), default="oe6dof")
    args = ap.parse_args()
    c = campaign_from_dict(card(args.method), "bench-20")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with TreeCpu() as cpu:
            result = campaign.run(c, Path(tmp) / "campaign", workers=args.workers)
        wall = time.perf_counter() - t0
    scores = result.scores
    failed = [s.index for s in scores if not s.estimated]
    shares = [s.share for s in scores if s.estimated]
    load = os.getloadavg()
    out = {"date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
           "points": c.n, "method": args.method, "workers": args.workers,
           "wall_s": round(wall, 1), "per_point_s": round(wall / c.n, 2),
           "cpu_s": round(cpu.seconds, 1), "cpu_per_point_s": round(cpu.seconds / c.n, 2),
           "cpu_wall_on_free_cores_s": round(cpu.seconds / args.workers, 1),
           "target_s": TARGET_S, "meets_target": wall <= TARGET_S,
           "failed_points": failed,
           "min_share_within_3_sigma": min(shares) if shares else None,
           "mean_share_within_3_sigma": sum(shares) / len(shares) if shares else None,
           "cpus": os.cpu_count(), "load_average_after": [round(x, 2) for x in load],
           "machine": platform.machine(), "python": platform.python_version(),
           "note": "measured on a machine shared with other users' jobs (load average "
                   "above)"}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"campaign_speed-{args.method}.json").write_text(json.dumps(out, indent=2) + "\n")
    lines = [f"20-point campaign (twinotter-id maneuvers, {args.method}), {args.workers} "
             f"workers, {out['date']}",
             f"python {out['python']}, {out['machine']}, {out['cpus']} CPUs; shared machine, "
             f"load average after the run {out['load_average_after']}",
             f"wall {out['wall_s']} s ({out['per_point_s']} s per point), target "
             f"<= {TARGET_S:g} s: {'met' if out['meets_target'] else 'missed'}",
             f"CPU {out['cpu_s']} s of the process tree ({out['cpu_per_point_s']} s per point):"
             f" {out['cpu_wall_on_free_cores_s']} s of wall on {args.workers} free cores",
             f"failed points: {failed or 'none'}; share of estimates within 3 sigma per "
             f"point: min {out['min_share_within_3_sigma']:.2f}, mean "
             f"{out['mean_share_within_3_sigma']:.2f}"]
    (RESULTS / f"campaign_speed-{args.method}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
