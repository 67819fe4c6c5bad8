"""Resident memory of a large Monte Carlo study on a ``dask.distributed.LocalCluster``.

Runs ``flightid.scenarios.montecarlo.run`` with ``dask_address`` on a LocalCluster of
``--workers`` single-threaded worker processes, on a cheap realization (a 9 s Navion
flight with one elevator doublet, research sensors, no turbulence, equation error on the
longitudinal model) so that many realizations fit in the time, and samples every
``--interval`` s, with psutil, the resident set size (RSS) of the client process (which
also hosts the scheduler and writes the Parquet rows) and of each worker process. Memory is
bounded when the RSS stops growing with the number of realizations done: the script
reports the RSS at 10 %, 50 % and 100 % of the study and the growth between the second
half's start and end per 1000 realizations. Writes benchmarks/results/montecarlo_memory.json.

    .venv/bin/python benchmarks/montecarlo_memory.py --n 1000 [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import psutil
from dask import distributed

from flightid.scenarios import montecarlo

RESULTS = Path(__file__).resolve().parent / "results" / "montecarlo_memory.json"
MB = 1024.0**2
CARD = """\
name = "navion-memory"
description = "cheap Monte Carlo realization: 9 s, one elevator doublet, research sensors"
aircraft = "navion"
duration = 9.0
rate = 100.0
seed = 7

[condition]
altitude = 0.0
speed = 53.64

[[maneuver]]
kind = "doublet"
surface = "de"
start = 1.0
base = 0.5
amplitude_deg = 3.0

[sensors]
suite = "research"
output_rate = 50.0
drop = ["vanes", "lever_arm"]
"""


def rss(pid: int) -> float:
    """Resident set size (MB) of process ``pid``, NaN if it is gone."""
    try:
        return psutil.Process(pid).memory_info().rss / MB
    except psutil.Error:
        return float("nan")


class Sampler(threading.Thread):
    """Samples the RSS of the client and the workers every ``interval`` s."""

    def __init__(self, workers: dict[str, int], interval: float) -> None:
        super().__init__(daemon=True)
        self.workers, self.interval = workers, interval
        self.samples: list[dict[str, Any]] = []
        self.done = 0
        self.stop = threading.Event()
        self.t0 = time.perf_counter()

    def sample(self) -> None:
        self.samples.append({"t": round(time.perf_counter() - self.t0, 2), "done": self.done,
                             "client_mb": round(rss(os.getpid()), 1),
                             "workers_mb": {w: round(rss(p), 1)
                                            for w, p in self.workers.items()}})

    def run(self) -> None:
        while not self.stop.wait(self.interval):
            self.sample()


def at(samples: list[dict[str, Any]], share: float, n: int) -> dict[str, Any]:
    """The first sample with at least ``share`` of the n realizations done."""
    for s in samples:
        if s["done"] >= share * n:
            return s
    return samples[-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--interval", type=float, default=1.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mc-memory-") as tmp:
        card = Path(tmp) / "navion-memory.toml"
        card.write_text(CARD)
        with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                      processes=True, dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            pids = client.run(os.getpid)  # {worker address: pid}
            sampler = Sampler(pids, args.interval)
            sampler.sample()
            start_client = sampler.samples[0]["client_mb"]

            def progress(done: int, total: int) -> None:
                sampler.done = done

            sampler.start()
            t0 = time.perf_counter()
            summary = montecarlo.run(str(card), args.n, "ee", "lon",
                                     study_dir=Path(tmp) / "study",
                                     dask_address=cluster.scheduler_address,
                                     progress=progress, report=False)
            wall = time.perf_counter() - t0
            sampler.stop.set()
            sampler.join()
            sampler.sample()
            stored = len(montecarlo.done(Path(tmp) / "study"))
    samples = sampler.samples
    n = args.n

    def snapshot(share: float) -> dict[str, Any]:
        s = at(samples, share, n)
        return {"done": s["done"], "client_mb": s["client_mb"],
                "workers_mb": s["workers_mb"]}

    half, end = at(samples, 0.5, n), at(samples, 1.0, n)
    per_k = 1000.0 / max(1, end["done"] - half["done"])
    growth = {"client_mb_per_1000": round((end["client_mb"] - half["client_mb"]) * per_k, 1),
              "workers_mb_per_1000": {w: round((end["workers_mb"][w] - half["workers_mb"][w])
                                               * per_k, 1) for w in pids}}
    doc = {
        "n": n, "workers": args.workers, "stored": stored, "wall_s": round(wall, 1),
        "realizations_per_s": round(n / wall, 2), "failures": summary.failures,
        "client_start_mb": start_client,
        "peak_client_mb": max(s["client_mb"] for s in samples),
        "peak_worker_mb": {w: max(s["workers_mb"][w] for s in samples) for w in pids},
        "at_10pct": snapshot(0.1), "at_50pct": snapshot(0.5), "at_100pct": snapshot(1.0),
        "growth_second_half": growth,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "load_average_end": os.getloadavg(),
                    "memory_total_mb": round(psutil.virtual_memory().total / MB)},
        "samples": samples,
    }
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(doc, indent=1) + "\n")
    print(json.dumps({k: v for k, v in doc.items() if k != "samples"}, indent=1))


if __name__ == "__main__":
    main()
