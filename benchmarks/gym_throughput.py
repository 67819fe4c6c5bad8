"""Steps per second of flightid/Excitation-v0 against bare JSBSim stepping; writes a results file.

Usage: python benchmarks/gym_throughput.py [out.txt] [--repeats N]

One 20 s episode of the default environment (Navion, 50 Hz decisions, research sensors,
lateral targets) under an aileron doublet, timed four ways on one core (process CPU time,
best of ``--repeats``, interleaved, median beside it):

- bare: ``FGFDMExec.run()`` for the same simulated time at the internal rate (400 Hz:
  8 runs per decision), nothing else;
- core: the flight core's ``Simulation.step`` once per decision (controls mapped, every
  property read, the sample converted to SI, departure checks);
- lean: the flight core's ``Simulation.stepper`` once per decision, reading the 17
  channels the environment uses, 19 JSBSim properties (what ``ExcitationEnv.step`` calls);
- env: ``ExcitationEnv.step`` (the core plus observation, information update, info) under
  the default reward (``valid-information``: the linear-range weight of each sample);
- env-information: the same under ``reward="information"`` (no weight);
- make: the same through ``gymnasium.make`` (its PassiveEnvChecker and OrderEnforcing
  wrappers).

Resets are outside the timed part. Each repeat runs every case once, back to back, so
``bare/case`` is given twice: from the best times, and as the median over the repeats of
that repeat's ratio (the A/B figure that the machine's load moves least).
"""

from __future__ import annotations

import argparse
import datetime
import platform
import statistics
import time
from pathlib import Path

import gymnasium
import jsbsim
import numpy as np

from flightid.scenarios.gym import ENV_ID, ExcitationEnv
from flightid.scenarios.gym.policies import doublet

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "gym_throughput.txt"


def main(out: Path, repeats: int = 5) -> str:
    env = ExcitationEnv()
    env_information = ExcitationEnv(reward="information")
    made = gymnasium.make(ENV_ID)
    actions = doublet(env, 0).astype(np.float32)
    n = env.n_decisions
    sim = env.sim
    substeps = sim.substeps * env.sim_per_decision
    increments = [{"de": 0.0, "da": float(a[1]) * 0.35, "dr": 0.0} for a in actions]

    def bare() -> float:
        sim.reset(env.trim)
        run = sim.model.fdm.run
        t0 = time.process_time()
        for _ in range(n * substeps):
            run()
        return time.process_time() - t0

    def core() -> float:
        sim.reset(env.trim)
        step = sim.step
        t0 = time.process_time()
        for inc in increments:
            step(inc)
        return time.process_time() - t0

    def lean() -> float:
        sim.reset(env.trim)
        advance = sim.stepper(env._read)
        t0 = time.process_time()
        for inc in increments:
            advance((inc["de"], inc["da"], inc["dr"]))
        return time.process_time() - t0

    def stepping(e) -> float:
        e.reset(seed=0)
        step = e.step
        t0 = time.process_time()
        for a in actions:
            step(a)
        return time.process_time() - t0

    cases = {"bare": bare, "core": core, "lean": lean, "env": lambda: stepping(env),
             "env-information": lambda: stepping(env_information),
             "make": lambda: stepping(made)}
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(repeats):
        for k, fn in cases.items():
            times[k].append(fn())
    best = {k: min(v) for k, v in times.items()}
    width = max(map(len, cases)) + 2
    lines = [f"flightid/Excitation-v0 throughput, {datetime.date.today().isoformat()}: "
             f"{env.aircraft}, {env.episode_s:g} s episode = {n} decisions at "
             f"{env.decision_hz:g} Hz, JSBSim internal {sim.internal_hz:g} Hz "
             f"({substeps} runs per decision); python {platform.python_version()}, "
             f"JSBSim {jsbsim.__version__}, {platform.machine()}; process CPU time, best "
             f"(median) of {repeats}", "",
             f"{'case':<{width}}{'steps/s':>10}{'(median)':>10}{'us/step':>10}{'bare/case':>11}"
             f"{'median ratio':>14}{'range':>12}"]
    for k in cases:
        ratios = [b / c for b, c in zip(times["bare"], times[k], strict=True)]
        lines.append(f"{k:<{width}}{n / best[k]:>10.0f}{n / statistics.median(times[k]):>10.0f}"
                     f"{best[k] / n * 1e6:>10.1f}{best['bare'] / best[k]:>11.2f}"
                     f"{statistics.median(ratios):>14.2f}"
                     f"{f'{min(ratios):.2f}-{max(ratios):.2f}':>12}")
    text = "\n".join(lines) + "\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(main(args.out, args.repeats))
