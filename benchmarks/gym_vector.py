"""Vector-environment throughput of flightid/Excitation-v0; writes a results file.

Usage: python benchmarks/gym_vector.py [out.txt] [--repeats N] [--workers N] [--chunks K ...]

Steps per second of wall-clock time (``time.perf_counter``; parallel work is what a
vector environment is for, so process CPU time would not show it), for one 20 s episode
per environment (1000 decisions at 50 Hz, a 3211 on aileron then rudder):

- single: one ``ExcitationEnv`` stepped in the main process;
- sync: ``gymnasium.vector.SyncVectorEnv`` of ``--workers`` environments (one process);
- async: ``gymnasium.vector.AsyncVectorEnv`` of ``--workers`` environments, one worker
  process each (shared-memory observations, the default);
- chunks K: the same with each environment wrapped in ``DecisionChunks`` (K decisions
  per worker call, for each K of ``--chunks``: one pipe round trip per chunk; the last
  call of an episode is padded with zero rows that are not flown, so any K >= 1 flies
  the whole episode, in one call when K is the episode's decisions or more).

Every case flies every environment's whole episode (checked: the last call truncates
all of them); steps count every environment's decision. The cases run interleaved,
``--repeats`` times; the speed-up is the median over the repeats of async / single (back
to back). Resets and the workers' start are outside the timed part, and so is a first,
uncounted round of every case (the first step in each process loads the compiled
kernels).

On a machine whose cores are busy with other work the wall-clock figures say little, so
the CPU time is counted too (``/proc``, summed over the repeats): the main process's and
the workers' CPU seconds per decision under async against the single environment's. Their
ratio is the efficiency of the vector (1: the pipe costs nothing); with ``--workers``
free cores async can step at most workers x efficiency x the single rate.

Where the time goes: the vector's own cost per decision in one process (sync CPU minus
single CPU per decision: stacking observations, merging ``info``), and per call of an
``AsyncVectorEnv`` of ``NullEnv`` (the spaces, no work) with and without the step's
``info`` (wall, and CPU of the main process and the workers), and pickling plus
unpickling that ``info``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import pickle
import platform
import statistics
import time
from collections.abc import Sequence
from functools import partial
from pathlib import Path

import gymnasium
import numpy as np
from gymnasium import spaces

from flightid.scenarios.gym import OBS_CHANNELS, DecisionChunks, ExcitationEnv
from flightid.scenarios.gym.policies import three211

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "gym_vector.txt"
TICK = os.sysconf("SC_CLK_TCK")
QUIET_CORES = 0.25  # a repeat is quiet when the rest of the machine used less than this


def machine_busy() -> float:
    """CPU seconds all cores have been busy since boot (``/proc/stat``: user, nice, system,
    irq, softirq, steal)."""
    fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]
    user, nice, system, _idle, _iowait, irq, softirq, steal = map(int, fields[:8])
    return (user + nice + system + irq + softirq + steal) / TICK


def others(busy0: float, own_cpu: float, wall: float) -> float:
    """Cores the rest of the machine used since ``machine_busy()`` was ``busy0``, given this
    run's CPU seconds in that time and the wall-clock seconds (a floor of 0)."""
    return max(machine_busy() - busy0 - own_cpu, 0.0) / wall


def cpu_seconds(pids: Sequence[int]) -> float:
    """User + system CPU seconds of the processes so far (``/proc/PID/stat``)."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15)
    return total / TICK


class NullEnv(gymnasium.Env):
    """The environment's spaces and no work: a step returns zeros and ``info`` (the
    vector's own cost per call)."""

    def __init__(self, info: dict | None = None) -> None:
        self.observation_space = spaces.Box(-np.inf, np.inf, (len(OBS_CHANNELS),), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        self.info = info or {}
        self.zeros = np.zeros(self.observation_space.shape)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        return self.zeros, dict(self.info)

    def step(self, action: np.ndarray):
        return self.zeros, 0.0, False, False, dict(self.info)


def pipe_costs(info: dict, calls: int = 2000, workers: int = 2) -> dict[str, float]:
    """Per call (us): pickling and unpickling ``info`` (one worker's reply); and wall
    and main-process + workers CPU time of ``AsyncVectorEnv`` of ``NullEnv`` with no
    ``info`` and with ``info``."""
    out = {}
    c0 = time.process_time()
    for _ in range(calls):
        pickle.loads(pickle.dumps(info))
    out["pickle info"] = (time.process_time() - c0) / calls * 1e6
    for name, inf in (("no info", {}), ("info", info)):
        venv = gymnasium.vector.AsyncVectorEnv([partial(NullEnv, inf)] * workers)
        venv.reset(seed=0)
        pids = [proc.pid for proc in venv.processes]
        action = np.zeros((workers, 3), np.float32)
        c0, w0, t0 = time.process_time(), cpu_seconds(pids), time.perf_counter()
        for _ in range(calls):
            venv.step(action)
        out[f"null {name}, wall"] = (time.perf_counter() - t0) / calls * 1e6
        out[f"null {name}, CPU main"] = (time.process_time() - c0) / calls * 1e6
        out[f"null {name}, CPU workers"] = (cpu_seconds(pids) - w0) / calls * 1e6
        venv.close()
    return out


def chunk_rows(batch: np.ndarray, k: int) -> np.ndarray:
    """The calls of ``DecisionChunks(env, k)`` workers that fly a whole episode.

    Parameters
    ----------
    batch : numpy.ndarray
        The episode's actions, ``(decisions, workers, 3)``.
    k : int
        Decisions per call, >= 1 (more than the episode's decisions: one call).

    Returns
    -------
    numpy.ndarray
        ``(calls, workers, k, 3)``, ``calls = ceil(decisions / k)``; the last call's rows
        past the episode's end are zeros, which ``DecisionChunks`` does not fly (the
        episode ends within that call).
    """
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"--chunks: decisions per call must be integers >= 1; got {k!r}")
    n, workers = batch.shape[:2]
    calls = -(-n // k)
    padded = np.zeros((calls * k, workers, 3), batch.dtype)
    padded[:n] = batch
    return padded.reshape(calls, k, workers, 3).swapaxes(1, 2)


def main(out: Path, repeats: int = 15, workers: int = 2, chunks: Sequence[int] = (10, 50),
         episodes: int = 2) -> str:
    single = ExcitationEnv()
    actions = three211(single, 0).astype(np.float32)
    n = len(actions)
    batch = np.repeat(actions[:, None, :], workers, axis=1)
    sync = gymnasium.vector.SyncVectorEnv([ExcitationEnv] * workers)
    asyn = gymnasium.vector.AsyncVectorEnv([ExcitationEnv] * workers)
    venvs = {"sync": (sync, [], batch), "async": (asyn, [p.pid for p in asyn.processes],
                                                  batch)}
    for k in chunks:
        chunked = gymnasium.vector.AsyncVectorEnv(
            [partial(lambda k: DecisionChunks(ExcitationEnv(), k), k)] * workers)
        venvs[f"chunks {k}"] = (chunked, [p.pid for p in chunked.processes],
                                chunk_rows(batch, k))
    cpu = {"single": 0.0, **{f"{k} {w}": 0.0 for k in venvs for w in ("main", "workers")}}
    decisions = {"single": n, **{k: workers * n for k in venvs}}  # whole episodes

    def one() -> tuple[float, float]:
        busy0, c_all, wall = machine_busy(), time.process_time(), 0.0
        for _ in range(episodes):
            single.reset(seed=0)
            step = single.step
            c0, t0 = time.process_time(), time.perf_counter()
            for a in actions:
                step(a)
            wall += time.perf_counter() - t0
            cpu["single"] += time.process_time() - c0
        own = time.process_time() - c_all
        return episodes * n / wall, others(busy0, own, wall)

    def vector(name: str) -> tuple[float, float]:
        venv, pids, rows = venvs[name]
        busy0, c_all, w_all, wall = machine_busy(), time.process_time(), cpu_seconds(pids), 0.0
        for _ in range(episodes):
            venv.reset(seed=list(range(workers)))
            step = venv.step
            c0, w0, t0 = time.process_time(), cpu_seconds(pids), time.perf_counter()
            for a in rows:
                truncated = step(a)[3]
            if not truncated.all():  # every environment flew its whole episode
                raise RuntimeError(f"{name}: an episode did not end with its last call")
            wall += time.perf_counter() - t0
            cpu[f"{name} main"] += time.process_time() - c0
            cpu[f"{name} workers"] += cpu_seconds(pids) - w0
        own = time.process_time() - c_all + cpu_seconds(pids) - w_all
        return episodes * decisions[name] / wall, others(busy0, own, wall)

    cases = {"single": one, **{k: partial(vector, k) for k in venvs}}
    rates: dict[str, list[float]] = {k: [] for k in cases}
    busy: dict[str, list[float]] = {k: [] for k in cases}  # cores the rest of the machine used
    loads = [os.getloadavg()[0]]
    for fn in cases.values():  # not counted: the first step in a process (the main one
        fn()                   # and each worker) compiles or loads the kernels
    cpu.update(dict.fromkeys(cpu, 0.0))
    for _ in range(repeats):
        for k, fn in cases.items():
            rate, rest = fn()
            rates[k].append(rate)
            busy[k].append(rest)
        loads.append(os.getloadavg()[0])
    for venv, _, _ in venvs.values():
        venv.close()
    single.reset(seed=0)
    info = single.step(actions[0])[4]
    pipe = pipe_costs(info, workers=workers)
    speedup = {k: [a / s for a, s in zip(rates[k], rates["single"], strict=True)]
               for k in venvs}
    quiet = {k: [r for r, a, b in zip(v, busy[k], busy["single"], strict=True)
                 if max(a, b) < QUIET_CORES] for k, v in speedup.items()}
    lines = [f"flightid/Excitation-v0 vector environments, {datetime.date.today().isoformat()}: "
             f"{single.aircraft}, {single.episode_s:g} s episodes = {n} decisions at "
             f"{single.decision_hz:g} Hz, {workers} environments per vector, chunks of "
             f"{', '.join(map(str, chunks))} decisions, "
             f"{os.cpu_count()} cores (shared with other work), python "
             f"{platform.python_version()}, gymnasium {gymnasium.__version__}; wall-clock "
             f"steps/s (all environments' decisions), best and median of {repeats}, "
             "interleaved", f"load average (1 min) over the run: {min(loads):.1f}-"
             f"{max(loads):.1f}, median {statistics.median(loads):.1f}", "",
             f"{episodes} episodes per case and repeat; 'rest': cores the rest of the machine "
             "used during the case (/proc/stat busy time less this run's processes), median; "
             f"'quiet': the repeats where the rest used < {QUIET_CORES} core during both "
             "cases of the ratio", "",
             f"{'case':<12}{'best':>8}{'median':>8}{'rest':>6}{'/ single: median':>18}"
             f"{'range':>12}{'quiet: n, median':>20}"]
    for k, v in rates.items():
        ratio = speedup.get(k)
        head = (f"{k:<12}{max(v):>8.0f}{statistics.median(v):>8.0f}"
                f"{statistics.median(busy[k]):>6.2f}")
        if not ratio:
            lines.append(head + f"{1:>18}")
            continue
        q = (f"{len(quiet[k]):>14d}, {statistics.median(quiet[k]):.2f}" if quiet[k]
             else f"{0:>14d}, -")
        lines.append(head + f"{statistics.median(ratio):>18.2f}{min(ratio):>7.2f}-"
                     f"{max(ratio):<5.2f}" + q)
    per = {k: v / (repeats * episodes * decisions[k.rsplit(' ', 1)[0]]) * 1e6
           for k, v in cpu.items()}
    lines += ["", "CPU time per decision (us; vectors: per decision of any environment)",
              *(f"  {k:<22}{v:>8.1f}" for k, v in per.items()), ""]
    for k in venvs:
        if k == "sync":
            continue
        efficiency = per["single"] / (per[f"{k} main"] + per[f"{k} workers"])
        lines.append(f"{k}: efficiency single / (main + workers) {efficiency:.2f}; on "
                     f"{workers} free cores it would step at most {workers * efficiency:.2f} x "
                     "single")
    lines += ["", f"where the time goes, per call of {workers} environments (us):",
              f"  sync - single, per decision (the vector's stacking and info merge): "
              f"{per['sync main'] - per['single']:.1f}",
              *(f"  {k:<28}{v:>8.1f}" for k, v in pipe.items()),
              f"  (the observation is {single.observation_space.shape[0]} float64 = "
              f"{single.observation_space.shape[0] * 8} bytes, in shared memory)"]
    text = "\n".join(lines) + "\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return text


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunks", type=int, nargs="+", default=[10, 50])
    parser.add_argument("--episodes", type=int, default=2, help="episodes per case and repeat")
    args = parser.parse_args()
    for name in ("repeats", "workers", "episodes"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1; got {getattr(args, name)}")
    if min(args.chunks) < 1:
        parser.error(f"--chunks: decisions per call must be >= 1; got {min(args.chunks)}")
    print(main(args.out, args.repeats, args.workers, args.chunks, args.episodes))
