"""Throughput of the flight core against bare JSBSim stepping; writes a results file.

Usage: python benchmarks/sim_throughput.py [out.json]
Bare: FGFDMExec.run() at the internal rate with nothing else. fly(): the same flight
through flightid.sim.flight (controls mapped, ~50 properties read per record sample,
departure checks, conversion to a FlightRecord). Ratio = bare time / fly time.
"""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

from flightid.sim.flight import Simulation, fly
from flightid.sim.model import load
from flightid.sim.trim import trim


def main(out: Path) -> dict:
    results = {}
    for name, alt, speed in (("c172p", 1000.0, 50.0), ("DHC6", 1920.0, 72.3)):
        model = load(name)
        t = trim(model, alt, speed)
        duration, rate = 60.0, 100.0
        de = 0.01 * np.sin(np.arange(int(duration * rate) + 1) / rate)
        start = time.perf_counter()
        fly(model, t, {"de": de}, duration, rate_hz=rate)
        t_fly = time.perf_counter() - start
        sim = Simulation(model, rate_hz=rate)
        sim.reset(t)
        fdm = sim.model.fdm
        steps = int(duration * sim.internal_hz)
        start = time.perf_counter()
        for _ in range(steps):
            fdm.run()
        t_bare = time.perf_counter() - start
        results[name] = {
            "simulated_s": duration, "record_hz": rate, "internal_hz": sim.internal_hz,
            "bare_wall_s": t_bare, "fly_wall_s": t_fly, "ratio_bare_over_fly": t_bare / t_fly,
            "realtime_factor_fly": duration / t_fly,
        }
    report = {"python": platform.python_version(), "machine": platform.machine(),
              "results": results}
    out.write_text(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    path = Path(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/sim_throughput.json")
    print(json.dumps(main(path), indent=1))
