"""Throughput of the flight core against bare JSBSim stepping; writes a results file.

Usage: python benchmarks/sim_throughput.py [out.json] [--repeats N]

Bare: FGFDMExec.run() at the internal rate with nothing else. fly(): the same flight
through flightid.sim.flight.simulation (controls mapped, the raw properties read every record
sample, departure checks, conversion to a FlightRecord; model copy and reset included).
step(): one ``Simulation.step`` with two control increments (a controller's call).
Each case runs ``--repeats`` times, interleaved; the best process CPU time counts (the
machine is shared) and the median is reported beside it. Ratio = bare / fly.
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import statistics
import time
from pathlib import Path

import jsbsim
import numpy as np

from flightid.sim.flight.simulation import Simulation, fly
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import trim

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "sim_throughput.json"
STEPS = 1000


def cpu_times(fn, repeats: int) -> list[float]:
    """Process CPU time (s) of each of ``repeats`` calls."""
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        out.append(time.process_time() - t0)
    return out


def main(out: Path, repeats: int = 7) -> dict:
    results = {}
    for name, alt, speed in (("c172p", 1000.0, 50.0), ("DHC6", 1920.0, 72.3)):
        model = load(name)
        t = trim(model, alt, speed)
        duration, rate = 60.0, 100.0
        de = 0.01 * np.sin(np.arange(int(duration * rate) + 1) / rate)
        sim = Simulation(model, rate_hz=rate)
        steps = int(duration * sim.internal_hz)

        def bare(sim=sim, t=t, steps=steps) -> None:
            sim.reset(t)
            run = sim.model.fdm.run
            for _ in range(steps):
                run()

        def flight(model=model, t=t, de=de, duration=duration, rate=rate) -> None:
            fly(model, t, {"de": de}, duration, rate_hz=rate)

        def stepping(sim=sim, t=t, de=de) -> None:
            sim.reset(t)
            for k in range(STEPS):
                sim.step({"de": de[k], "da": 0.001})

        times: dict[str, list[float]] = {"bare": [], "fly": [], "step": []}
        for _ in range(repeats):  # interleaved: a busy spell slows all three alike
            for key, fn in (("bare", bare), ("fly", flight), ("step", stepping)):
                times[key] += cpu_times(fn, 1)
        best = {k: min(v) for k, v in times.items()}
        results[name] = {
            "simulated_s": duration, "record_hz": rate, "internal_hz": sim.internal_hz,
            "bare_cpu_s": best["bare"], "bare_cpu_median_s": statistics.median(times["bare"]),
            "fly_cpu_s": best["fly"], "fly_cpu_median_s": statistics.median(times["fly"]),
            "ratio_bare_over_fly": best["bare"] / best["fly"],
            "realtime_factor_fly": duration / best["fly"],
            "step_us": best["step"] / STEPS * 1e6,
            "step_us_median": statistics.median(times["step"]) / STEPS * 1e6,
        }
    report = {"date": datetime.date.today().isoformat(), "repeats": repeats,
              "python": platform.python_version(), "jsbsim": jsbsim.__version__,
              "machine": platform.machine(), "results": results}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(json.dumps(main(args.out, args.repeats), indent=1))
