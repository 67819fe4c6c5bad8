"""Vector-environment throughput of flightid/Excitation-v0; writes a results file.

Usage: python benchmarks/gym_vector.py [out.txt] [--repeats N] [--workers N] [--chunk K]

Steps per second of wall-clock time (``time.perf_counter``; parallel work is what a
vector environment is for, so process CPU time would not show it), for one 20 s episode
per environment (1000 decisions at 50 Hz, a 3211 on aileron then rudder):

- single: one ``ExcitationEnv`` stepped in the main process;
- sync: ``gymnasium.vector.SyncVectorEnv`` of ``--workers`` environments (one process);
- async: ``gymnasium.vector.AsyncVectorEnv`` of ``--workers`` environments, one worker
  process each (shared-memory observations, the default);
- async-chunks: the same with each environment wrapped in ``DecisionChunks`` (``--chunk``
  decisions per worker call: one pipe round trip per chunk).

Steps count every environment's decision. The cases run interleaved, ``--repeats`` times;
the speed-up is the median over the repeats of async / single (back to back). Resets and
the workers' start are outside the timed part.

On a machine whose cores are busy with other work the wall-clock figures say little, so
the CPU time is counted too (``/proc``, summed over the repeats): the main process's and
the workers' CPU seconds per decision under async against the single environment's. Their
ratio is the efficiency of the vector (1: the pipe costs nothing); with ``--workers``
free cores async can step at most workers x efficiency x the single rate.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import time
from collections.abc import Sequence
from pathlib import Path

import gymnasium
import numpy as np

from flightid.scenarios.gym import DecisionChunks, ExcitationEnv
from flightid.scenarios.gym.baselines import three211

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "gym_vector.txt"
TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pids: Sequence[int]) -> float:
    """User + system CPU seconds of the processes so far (``/proc/PID/stat``)."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15)
    return total / TICK


def main(out: Path, repeats: int = 15, workers: int = 2, chunk: int = 10) -> str:
    single = ExcitationEnv()
    actions = three211(single, 0).astype(np.float32)
    n = len(actions)
    batch = np.repeat(actions[:, None, :], workers, axis=1)
    sync = gymnasium.vector.SyncVectorEnv([ExcitationEnv] * workers)
    asyn = gymnasium.vector.AsyncVectorEnv([ExcitationEnv] * workers)
    chunked = gymnasium.vector.AsyncVectorEnv(
        [lambda: DecisionChunks(ExcitationEnv(), chunk)] * workers)
    n_chunks = (n - 1) // chunk  # whole chunks before the episode's last decision
    chunks = batch[:n_chunks * chunk].reshape(n_chunks, chunk, workers, 3).swapaxes(1, 2)

    workers_pids = [proc.pid for proc in asyn.processes]
    chunked_pids = [proc.pid for proc in chunked.processes]
    cpu = {"single": 0.0, "async main": 0.0, "async workers": 0.0,
           "async-chunks main": 0.0, "async-chunks workers": 0.0}

    def one() -> float:
        single.reset(seed=0)
        step = single.step
        c0, t0 = time.process_time(), time.perf_counter()
        for a in actions:
            step(a)
        t1 = time.perf_counter()
        cpu["single"] += time.process_time() - c0
        return n / (t1 - t0)

    def vector(venv: gymnasium.vector.VectorEnv, pids: Sequence[int] = (), name: str = "async",
               actions: np.ndarray = batch[:-1]) -> float:
        venv.reset(seed=list(range(workers)))
        step = venv.step
        c0, w0, t0 = time.process_time(), cpu_seconds(pids), time.perf_counter()
        for a in actions:  # (the episode's last step would autoreset)
            step(a)
        t1 = time.perf_counter()
        if pids:
            cpu[f"{name} main"] += time.process_time() - c0
            cpu[f"{name} workers"] += cpu_seconds(pids) - w0
        return actions.shape[0] * (actions.size // actions.shape[0] // 3) / (t1 - t0)

    cases = {"single": one, "sync": lambda: vector(sync),
             "async": lambda: vector(asyn, workers_pids),
             "async-chunks": lambda: vector(chunked, chunked_pids, "async-chunks", chunks)}
    rates: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(repeats):
        for k, fn in cases.items():
            rates[k].append(fn())
    load = os.getloadavg()
    sync.close()
    asyn.close()
    chunked.close()
    speedup = {k: [a / s for a, s in zip(rates[k], rates["single"], strict=True)]
               for k in ("async", "async-chunks")}
    lines = [f"flightid/Excitation-v0 vector environments, {datetime.date.today().isoformat()}: "
             f"{single.aircraft}, {single.episode_s:g} s episodes = {n} decisions at "
             f"{single.decision_hz:g} Hz, {workers} environments per vector, chunks of "
             f"{chunk} decisions, "
             f"{os.cpu_count()} cores (shared with other work), python "
             f"{platform.python_version()}, gymnasium {gymnasium.__version__}; wall-clock "
             f"steps/s (all environments' decisions), best and median of {repeats}, "
             "interleaved", "",
             f"{'case':<10}{'best':>10}{'median':>10}"]
    for k, v in rates.items():
        lines.append(f"{k:<10}{max(v):>10.0f}{statistics.median(v):>10.0f}")
    decisions = {"single": n, "async": (n - 1) * workers, "async-chunks": n_chunks * chunk
                 * workers}
    per = {k: v / (repeats * decisions[k.split()[0]]) * 1e6 for k, v in cpu.items()}
    lines.append("")
    for k, ratios in speedup.items():
        lines.append(f"{k} / single, median of the {repeats} back-to-back ratios: "
                     f"{statistics.median(ratios):.2f} (range {min(ratios):.2f}-"
                     f"{max(ratios):.2f})")
    lines += [f"load average at the end {load[0]:.1f} on {os.cpu_count()} cores", "",
              "CPU time per decision (us; async: per decision of any environment)",
              *(f"  {k:<22}{v:>8.1f}" for k, v in per.items()), ""]
    for k in ("async", "async-chunks"):
        efficiency = per["single"] / (per[f"{k} main"] + per[f"{k} workers"])
        lines.append(f"{k}: efficiency single / (main + workers) {efficiency:.2f}; on "
                     f"{workers} free cores it would step at most {workers * efficiency:.2f} x "
                     "single")
    text = "\n".join(lines) + "\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk", type=int, default=10)
    args = parser.parse_args()
    print(main(args.out, args.repeats, args.workers, args.chunk))
