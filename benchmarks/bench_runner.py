"""Throughput of the scenario runner: simulated seconds per wall second.

Compares ``fly_card`` (without sensors and with the card's research suite, light
turbulence on) with bare JSBSim stepping of the same aircraft at the same internal rate
(``jsbsim.FGFDMExec.run`` in a Python loop, nothing read). The runner must keep at least
70 % of the bare throughput. Writes benchmarks/results/runner.txt.

    .venv/bin/python benchmarks/bench_runner.py
"""

from __future__ import annotations

import copy
import platform
import time
from pathlib import Path

import jsbsim

from flightid.scenarios.cards import card_from_dict, fly_card, load_card
from flightid.sim.flight import MIN_INTERNAL_HZ
from flightid.sim.model import load
from flightid.sim.trim import apply, trim

REPEATS = 7
DURATION_S = 60.0
RESULTS = Path(__file__).resolve().parent / "results" / "runner.txt"


def best_of(cases: list, repeats: int = REPEATS) -> list[float]:
    """Smallest wall time (s) of each case over ``repeats`` rounds, the cases interleaved
    so that a busy machine slows them alike; the minimum is the least disturbed run."""
    best = [float("inf")] * len(cases)
    for _ in range(repeats):
        for i, fn in enumerate(cases):
            t0 = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best


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


def main() -> str:
    demo = load_card("navion-demo")
    data = copy.deepcopy(demo.data)
    data["duration"] = DURATION_S
    with_sensors = card_from_dict(data, "navion-demo (60 s)")
    data_ns = {k: v for k, v in data.items() if k != "sensors"}
    no_sensors = card_from_dict(data_ns, "navion-demo (60 s, no sensors)")
    calm = card_from_dict({k: v for k, v in data_ns.items() if k != "disturbance"},
                          "navion-demo (60 s, no sensors, calm)")
    internal = max(MIN_INTERNAL_HZ, demo.rate)
    cases = [("bare JSBSim FGFDMExec.run loop",
              bare_jsbsim(demo.aircraft, demo.condition.altitude_m, demo.condition.speed_m_s,
                          internal))]
    for label, card in (("fly_card, no sensors, calm air", calm),
                        ("fly_card, no sensors, light turbulence", no_sensors),
                        ("fly_card, research sensors, light turbulence", with_sensors)):
        cases.append((label, lambda c=card: fly_card(c, seed=1)))
    rows = list(zip([c[0] for c in cases], best_of([c[1] for c in cases]), strict=True))
    bare = rows[0][1]
    lines = [
        "flightid scenario runner benchmark (benchmarks/bench_runner.py)",
        f"aircraft {demo.aircraft}, {DURATION_S:g} s flights, record {demo.rate:g} Hz, "
        f"JSBSim internal {internal:g} Hz; best of {REPEATS}",
        f"jsbsim {jsbsim.__version__}, python {platform.python_version()}, "
        f"{platform.machine()} {platform.processor() or ''}".rstrip(),
        "",
        f"{'case':48s} {'wall s':>8s} {'sim s / wall s':>15s} {'of bare':>8s}",
    ]
    for label, wall in rows:
        lines.append(f"{label:48s} {wall:8.3f} {DURATION_S / wall:15.1f} "
                     f"{bare / wall:8.0%}")
    worst = min(bare / w for _, w in rows[1:])
    lines += ["", f"requirement: runner keeps >= 70 % of bare throughput: "
                  f"{'met' if worst >= 0.7 else 'NOT met'} (worst {worst:.0%})"]
    text = "\n".join(lines) + "\n"
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(text, encoding="utf-8")
    return text


if __name__ == "__main__":
    print(main(), end="")
