"""Throughput of the scenario runner: simulated seconds per second of computing.

Compares ``fly_card`` (without sensors in calm air and in light turbulence, and with the
card's research suite) with bare JSBSim stepping of the same aircraft at the same
internal rate (``jsbsim.FGFDMExec.run`` in a Python loop, nothing read). The runner must
keep at least 70 % of the bare throughput. Also times the flight loop alone
(``Simulation.fly`` from a trim, no load or trim) and one ``Simulation.step``.

The machine is shared, so each case runs REPEATS times, the cases interleaved so that a
busy spell slows them alike; the table gives the best (least disturbed) run and the
spread (median and worst) of the process CPU time, and the best wall time. The
requirement is judged on the best CPU times (wall times of other processes' spells are
not the runner's). ``--baseline FILE`` also times ``fly`` and ``step`` of another
version of ``sim/flight/simulation.py``
(e.g. ``git show HEAD:sim/flight/simulation.py > /tmp/old_flight.py``).
Writes benchmarks/results/runner.txt.

    .venv/bin/python benchmarks/bench_runner.py [--repeats 15] [--baseline FILE]
"""

from __future__ import annotations

import argparse
import copy
import datetime
import importlib.util
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import jsbsim
import numpy as np

from flightid.scenarios.cards import card_from_dict, fly_card, load_card
from flightid.sim.flight.simulation import MIN_INTERNAL_HZ
from flightid.sim.jsbsim.model import load
from flightid.sim.jsbsim.trim import apply, trim

REPEATS = 15
DURATION_S = 60.0
STEPS = 2000  # Simulation.step calls per timing of step()
RESULTS = Path(__file__).resolve().parent / "results" / "runner.txt"


def timings(cases: list[Callable[[], None]], repeats: int) -> list[tuple[list[float], float]]:
    """Per case: (CPU times of every round in s, best wall time in s), rounds interleaved."""
    cpu: list[list[float]] = [[] for _ in cases]
    wall = [float("inf")] * len(cases)
    for _ in range(repeats):
        for i, fn in enumerate(cases):
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            cpu[i].append(time.process_time() - c0)
            wall[i] = min(wall[i], time.perf_counter() - w0)
    return list(zip(cpu, wall, strict=True))


def bare_jsbsim(aircraft: str, altitude: float, speed: float, rate_hz: float):
    """A callable flying DURATION_S simulated seconds of FGFDMExec.run from trim."""
    model = load(aircraft)
    tr = trim(model, altitude, speed)
    fdm = model.fdm
    steps = int(round(DURATION_S * rate_hz))

    def run() -> None:
        apply(model, tr)
        fdm.set_dt(1.0 / rate_hz)
        step = fdm.run
        for _ in range(steps):
            step()

    return run


def loop_only(flight_module, aircraft: str, altitude: float, speed: float, rate_hz: float,
              controls: dict[str, np.ndarray]):
    """A callable flying the card's inputs with ``Simulation.fly`` of a flight module."""
    tr = trim(load(aircraft), altitude, speed)
    if hasattr(flight_module.Simulation, "fly"):
        sim = flight_module.Simulation(aircraft, rate_hz=rate_hz)
        return lambda: sim.fly(tr, controls, DURATION_S)
    return lambda: flight_module.fly(aircraft, tr, controls, DURATION_S, rate_hz)


def stepper(flight_module, aircraft: str, altitude: float, speed: float, rate_hz: float):
    """A callable making STEPS calls of ``Simulation.step`` with an elevator sine."""
    tr = trim(load(aircraft), altitude, speed)
    sim = flight_module.Simulation(aircraft, rate_hz=rate_hz)
    de = (0.01 * np.sin(np.arange(STEPS) / rate_hz)).tolist()

    def run() -> None:
        sim.reset(tr)
        step = sim.step
        for k in range(STEPS):
            step({"de": de[k], "da": 0.001})

    return run


def load_flight_module(path: Path):
    """Import another version of sim/flight/simulation.py under its own name."""
    spec = importlib.util.spec_from_file_location("flight_baseline", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def main(repeats: int = REPEATS, baseline: Path | None = None) -> str:
    from flightid.scenarios.inputs import total_signals
    from flightid.sim.flight import simulation as flight

    demo = load_card("navion-demo")
    data = copy.deepcopy(demo.data)
    data["duration"] = DURATION_S
    with_sensors = card_from_dict(data, "navion-demo (60 s)")
    data_ns = {k: v for k, v in data.items() if k != "sensors"}
    no_sensors = card_from_dict(data_ns, "navion-demo (60 s, no sensors)")
    calm = card_from_dict({k: v for k, v in data_ns.items() if k != "disturbance"},
                          "navion-demo (60 s, no sensors, calm)")
    c = demo.condition
    internal = max(MIN_INTERNAL_HZ, demo.rate)
    n = int(round(DURATION_S * demo.rate)) + 1
    controls = total_signals(calm.maneuvers, np.arange(n) / demo.rate)
    where = (demo.aircraft, c.altitude_m, c.speed_m_s, demo.rate)
    flights = [("bare JSBSim FGFDMExec.run loop",
                bare_jsbsim(demo.aircraft, c.altitude_m, c.speed_m_s, internal))]
    for label, card in (("fly_card, no sensors, calm air", calm),
                        ("fly_card, no sensors, light turbulence", no_sensors),
                        ("fly_card, research sensors, light turbulence", with_sensors)):
        flights.append((label, lambda card=card: fly_card(card, seed=1)))
    flights.append(("Simulation.fly from trim (calm; no load, trim)",
                    loop_only(flight, *where, controls)))
    steps = [("Simulation.step", stepper(flight, *where))]
    if baseline is not None:
        old = load_flight_module(baseline)
        flights.append(("baseline: fly from trim (calm; no load, trim)",
                        loop_only(old, *where, controls)))
        steps.append(("baseline: Simulation.step", stepper(old, *where)))
    cases = flights + steps
    results = timings([fn for _, fn in cases], repeats)
    bare = min(results[0][0])
    lines = [
        "flightid scenario runner benchmark (benchmarks/bench_runner.py)",
        f"run {datetime.date.today().isoformat()}; aircraft {demo.aircraft}, {DURATION_S:g} s "
        f"flights, record {demo.rate:g} Hz, JSBSim internal {internal:g} Hz; "
        f"{repeats} rounds, cases interleaved",
        f"jsbsim {jsbsim.__version__}, python {platform.python_version()}, numpy "
        f"{np.__version__}, {platform.machine()} {platform.processor() or ''}".rstrip(),
        "CPU = process CPU time (best / median / worst of the rounds); wall = best wall time;",
        "sim s / CPU s and 'of bare' from the best CPU times",
        "",
        f"{'flight (60 s simulated)':50s} {'CPU best':>9s} {'median':>7s} {'worst':>7s} "
        f"{'wall':>7s} {'sim s/CPU s':>12s} {'of bare':>8s}",
    ]
    for (label, _), (cpu, wall) in zip(flights, results[:len(flights)], strict=True):
        best = min(cpu)
        lines.append(f"{label:50s} {best:9.3f} {statistics.median(cpu):7.3f} {max(cpu):7.3f} "
                     f"{wall:7.3f} {DURATION_S / best:12.1f} {bare / best:8.0%}")
    lines += ["", f"{'one record step (' + str(STEPS) + ' calls)':50s} {'us best':>9s} "
                  f"{'median':>7s} {'worst':>7s}"]
    for (label, _), (cpu, _) in zip(steps, results[len(flights):], strict=True):
        us = [t / STEPS * 1e6 for t in cpu]
        lines.append(f"{label:50s} {min(us):9.1f} {statistics.median(us):7.1f} {max(us):7.1f}")
    runner = [bare / min(cpu) for cpu, _ in results[1:4]]
    worst = min(runner)
    lines += ["", f"requirement: runner keeps >= 70 % of bare throughput: "
                  f"{'met' if worst >= 0.7 else 'NOT met'} (worst case {worst:.0%})"]
    text = "\n".join(lines) + "\n"
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(text, encoding="utf-8")
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=REPEATS)
    parser.add_argument("--baseline", type=Path, default=None,
                        help="another sim/flight/simulation.py to time fly and step against")
    args = parser.parse_args()
    print(main(args.repeats, args.baseline), end="")
