"""Where a vector environment of flightid/Excitation-v0 loses against its workers x the
single environment: one case per process, for a whole-process timer run A B A B.

Usage: python benchmarks/gym_vector_profile.py CASE [--episodes N] [--workers W] [--chunk K]
                                                    [--pin]
       python benchmarks/gym_vector_profile.py --summarize FILE [FILE ...]

Every case flies the same decisions: W x N episodes of 20 s (1000 decisions at 50 Hz, a
3211 on aileron then rudder; seeds 0 to W N - 1), after one uncounted episode in each
process (the first step in a process loads the compiled kernels). Cases:

- ``single``: one ``ExcitationEnv`` in this process, episode after episode;
- ``procs``: W processes of one ``ExcitationEnv`` each, N episodes each, started
  together and never talking while they fly: the most any vector of W workers can give
  on this machine (what its cores give two independent simulations);
- ``async``: ``gymnasium.vector.AsyncVectorEnv`` of W workers, K decisions per worker
  call (``DecisionChunks``; K = 1: the plain environment), N episodes per worker.

Each prints one JSON line: wall seconds stepping (resets apart), per decision of one
environment (``single``: per decision; a vector: per call of all W / K, so that
``speedup = W x single / vector``), and for ``async`` that wall split into the parts of
each call, from ``time.perf_counter`` in the main process and in each worker around its
``step`` (one clock for all processes) and ``time.thread_time`` in the worker:

- ``cpu``: the workers' CPU in ``step`` (mean over the workers);
- ``off_cpu``: a worker's wall in ``step`` less its CPU (the kernel ran something else);
- ``straggler``: the slowest worker's wall in ``step`` less the mean (the others wait);
- ``pipe``: the main process's wall for the call less the slowest worker's wall in
  ``step`` (sending the actions, the workers' wake-up, the replies, merging ``info``);

and, what free cores would see, CPU only: ``cpu_straggler`` (the slower worker's CPU in
``step`` less the mean), ``workers_pipe_cpu`` (a worker's CPU outside ``step``: the
pipe's work, from ``/proc``) and ``main_cpu`` (the main process's); the time a worker
waited for a processor (``/proc/thread-self/schedstat``) in ``step`` (``runq_in_step``)
and once woken by the main process's message (``runq_woken``); ``same_cpu``, the share of
calls at whose start both workers were on one processor. ``--pin`` holds worker i to
processor i. ``--autoreset NextStep|SameStep``: the vector resets its workers itself
(that ``autoreset_mode``), worker i's episodes 20 (1 - 0.15 i) s long so that they end in
different calls; it prints the share of each worker's calls that flew no decision
(``idle_share``: under NextStep the call after an episode's end only resets) and the
decisions flown. Every case also gives the cores the whole machine used (``machine_cores``,
this run included) and the hypervisor's steal (``steal_cores``).

``--summarize`` reads files of such lines (one run's output appended per run) and prints
the medians per case and the speed-ups of the pairs in the order the runs were made.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import sys
import time
from functools import partial
from pathlib import Path

import gymnasium
import numpy as np

from flightid.scenarios.gym import DecisionChunks, ExcitationEnv
from flightid.scenarios.gym.policies import three211

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling script, from anywhere
from gym_vector import chunk_rows, cpu_seconds, machine_busy  # noqa: E402

CASES = ("single", "procs", "async")


def sched_now() -> tuple[int, float]:
    """This thread's processor and its seconds so far runnable but waiting for one
    (``/proc/thread-self/stat`` field 39, ``/proc/thread-self/schedstat`` field 2)."""
    stat = Path("/proc/thread-self/stat").read_text().rsplit(")", 1)[1].split()
    waited = int(Path("/proc/thread-self/schedstat").read_text().split()[1])
    return int(stat[36]), waited / 1e9


class Timed(gymnasium.Wrapper):
    """Records each ``step`` call: its start and end (``time.perf_counter``), the thread's
    CPU seconds in it (``time.thread_time``), the seconds it waited for a processor in it
    and since the previous call ended (woken by the main process's message), and the
    processor at its start."""

    def __init__(self, env: gymnasium.Env) -> None:
        super().__init__(env)
        self.calls: list[tuple[float, ...]] = []
        self.flown: list[int] = []  # decisions flown in each call
        self._waited = sched_now()[1]

    def step(self, action):
        cpu0, waited0 = sched_now()
        k0 = self.env.unwrapped._k
        t0, c0 = time.perf_counter(), time.thread_time()
        out = self.env.step(action)
        t1, c1 = time.perf_counter(), time.thread_time()
        waited1 = sched_now()[1]
        self.calls.append((t0, t1, c1 - c0, waited1 - waited0, waited0 - self._waited, cpu0))
        self.flown.append(self.env.unwrapped._k - k0)
        self._waited = waited1
        return out

    def clear(self) -> None:
        """Forget the calls so far."""
        self.calls, self.flown = [], []


def timed_env(k: int, cpu: int | None = None, episode_s: float = 20.0) -> gymnasium.Env:
    """A worker's environment: ``DecisionChunks`` of ``k`` (none for 1), timed; with
    ``cpu``, the worker process is held to that processor."""
    if cpu is not None:
        os.sched_setaffinity(0, {cpu})
    env = ExcitationEnv(episode_s=episode_s)
    return Timed(env if k == 1 else DecisionChunks(env, k))


def fly(env: ExcitationEnv, actions: np.ndarray, seeds: list[int]) -> dict[str, float]:
    """Fly one episode per seed; wall and CPU seconds of the steps, wall of the resets."""
    out = {"step_wall": 0.0, "step_cpu": 0.0, "reset_wall": 0.0}
    for seed in seeds:
        t0 = time.perf_counter()
        env.reset(seed=seed)
        t1, c1 = time.perf_counter(), time.process_time()
        for a in actions:
            env.step(a)
        out["step_wall"] += time.perf_counter() - t1
        out["step_cpu"] += time.process_time() - c1
        out["reset_wall"] += t1 - t0
    return out


def proc_worker(actions, seeds, barrier, queue) -> None:
    """One ``procs`` process: load the kernels, wait for the others, fly, report."""
    env = ExcitationEnv()
    fly(env, actions, [10_000])
    barrier.wait()
    queue.put(fly(env, actions, seeds))


def run(case: str, episodes: int, workers: int, chunk: int, pin: bool = False,
        autoreset: str | None = None) -> dict:
    """One case's figures (module docstring): seconds, and per decision in us."""
    actions = three211(ExcitationEnv(), 0).astype(np.float32)
    n = len(actions)
    seeds = list(range(workers * episodes))
    out = {"case": case, "episodes": episodes, "workers": workers, "decisions": n,
           "load": os.getloadavg()[0]}
    busy0, steal0, start = machine_busy(), steal_seconds(), time.perf_counter()
    if case == "single":
        env = ExcitationEnv()
        fly(env, actions, [10_000])
        got = fly(env, actions, seeds)
        out.update(got, wall_per_decision=got["step_wall"] / len(seeds) / n * 1e6,
                   cpu_per_decision=got["step_cpu"] / len(seeds) / n * 1e6)
    elif case == "procs":
        ctx = multiprocessing.get_context("fork")
        barrier, queue = ctx.Barrier(workers + 1), ctx.Queue()
        procs = [ctx.Process(target=proc_worker, args=(actions, seeds[i::workers], barrier,
                                                      queue)) for i in range(workers)]
        for p in procs:
            p.start()
        barrier.wait()
        t0 = time.perf_counter()
        got = [queue.get() for _ in procs]
        wall = time.perf_counter() - t0
        for p in procs:
            p.join()
        out.update(step_wall=wall, wall_per_decision=wall / episodes / n * 1e6,
                   cpu_per_decision=sum(g["step_cpu"] for g in got) / len(seeds) / n * 1e6,
                   worker_wall_per_decision=max(g["step_wall"] for g in got)
                   / episodes / n * 1e6)
    elif autoreset:
        out.update(autoreset_profile(actions, episodes * len(chunk_rows(actions[:, None], chunk)),
                                     workers, chunk, autoreset))
    else:
        out.update(async_profile(actions, episodes, workers, chunk, pin))
    wall = time.perf_counter() - start
    # cores busy on the whole machine during the case (this run's processes included;
    # 2 workers alone make about 2) and the hypervisor's steal time, in cores
    out.update(machine_cores=(machine_busy() - busy0) / wall,
               steal_cores=(steal_seconds() - steal0) / wall)
    return out


def steal_seconds() -> float:
    """Seconds all cores' time was taken by the hypervisor since boot (``/proc/stat``)."""
    return int(Path("/proc/stat").read_text().split("\n", 1)[0].split()[8]) / os.sysconf(
        "SC_CLK_TCK")


def async_profile(actions: np.ndarray, episodes: int, workers: int, chunk: int,
                  pin: bool = False) -> dict:
    """The ``async`` case: wall and its split per call (module docstring)."""
    n = len(actions)
    batch = np.repeat(actions[:, None], workers, axis=1)
    rows = batch if chunk == 1 else chunk_rows(batch, chunk)
    cpus = sorted(os.sched_getaffinity(0))
    venv = gymnasium.vector.AsyncVectorEnv(
        [partial(timed_env, chunk, cpus[i % len(cpus)] if pin else None) for i in range(workers)])
    pids = [p.pid for p in venv.processes]
    main_calls, reset_wall, main_cpu, workers_cpu = [], 0.0, 0.0, 0.0
    try:
        for e in range(-1, episodes):  # episode -1: loads the kernels, not counted
            t0 = time.perf_counter()
            venv.reset(seed=[10_000 + i if e < 0 else e * workers + i
                             for i in range(workers)])
            if e == 0:
                venv.call("clear")
                main_calls, reset_wall, main_cpu, workers_cpu = [], 0.0, 0.0, 0.0
            reset_wall += time.perf_counter() - t0
            c0, w0 = time.process_time(), cpu_seconds(pids)
            for a in rows:
                t1 = time.perf_counter()
                truncated = venv.step(a)[3]
                main_calls.append((t1, time.perf_counter()))
            main_cpu += time.process_time() - c0
            workers_cpu += cpu_seconds(pids) - w0
            if not truncated.all():
                raise RuntimeError("an episode did not end with its last call")
        worker_calls = np.array(venv.get_attr("calls"))  # (workers, calls, 3)
    finally:
        venv.close()
    main = np.array(main_calls)
    wall = main[:, 1] - main[:, 0]
    d = worker_calls[..., 1] - worker_calls[..., 0]
    c = worker_calls[..., 2]
    parts = {"cpu": c.mean(axis=0).sum(), "off_cpu": (d - c).mean(axis=0).sum(),
             "straggler": (d.max(axis=0) - d.mean(axis=0)).sum(),
             "pipe": (wall - d.max(axis=0)).sum(),
             # CPU only (what free cores would see): the slower worker's CPU less the mean,
             # the workers' CPU outside step (the pipe's work) and the main process's
             "cpu_straggler": (c.max(axis=0) - c.mean(axis=0)).sum(),
             "workers_pipe_cpu": workers_cpu / workers - c.mean(axis=0).sum(),
             "main_cpu": main_cpu,
             # waiting for a processor (runnable, not running): in step, and once woken
             "runq_in_step": worker_calls[..., 3].mean(axis=0).sum(),
             "runq_woken": worker_calls[..., 4].mean(axis=0).sum()}
    per = 1e6 / (episodes * n)
    return {"chunk": chunk, "step_wall": wall.sum(), "reset_wall": reset_wall,
            "wall_per_decision": wall.sum() * per,
            **{f"{k}_per_decision": v * per for k, v in parts.items()},
            "pipe_per_call": parts["pipe"] / len(wall) * 1e6, "pinned": pin,
            "same_cpu": float(np.mean(np.ptp(worker_calls[..., 5], axis=0) == 0))}




def autoreset_profile(actions: np.ndarray, calls: int, workers: int, chunk: int,
                      mode: str) -> dict:
    """``calls`` calls of an ``AsyncVectorEnv`` that resets its workers itself
    (``autoreset_mode`` ``mode``), worker i's episodes 20 (1 - 0.15 i) s long, so that they
    end in different calls: the share of each worker's calls that flew no decision, and
    the decisions flown per second of wall clock and per CPU second of the workers."""
    lengths = [20.0 * (1 - 0.15 * i) for i in range(workers)]
    rows = chunk_rows(np.repeat(actions[:, None], workers, axis=1), chunk)
    venv = gymnasium.vector.AsyncVectorEnv(
        [partial(timed_env, chunk, None, s) for s in lengths],
        autoreset_mode=gymnasium.vector.AutoresetMode(mode),
        observation_mode="different")  # (the bound of t is the episode's length)
    pids = [p.pid for p in venv.processes]
    try:
        venv.reset(seed=list(range(workers)))
        for j in range(len(rows) + 1):  # loads the kernels, not counted
            venv.step(rows[j % len(rows)])
        venv.call("clear")
        w0, t0 = cpu_seconds(pids), time.perf_counter()
        for j in range(calls):
            venv.step(rows[j % len(rows)])
        wall, cpu = time.perf_counter() - t0, cpu_seconds(pids) - w0
        flown = venv.get_attr("flown")
    finally:
        venv.close()
    total = sum(map(sum, flown))
    return {"chunk": chunk, "autoreset": mode, "calls": calls, "episode_s": lengths,
            "idle_share": [1 - sum(1 for f in w if f) / calls for w in flown],
            "decisions_flown": total, "flown_per_s": total / wall,
            "wall_per_decision": wall / total * workers * 1e6,
            "workers_cpu_per_decision": cpu / total * 1e6}


def summarize(files: list[Path], skip: int = 1) -> str:
    """Medians per case, and run-by-run speed-ups of cases with as many runs, from files
    of JSON lines, the first ``skip`` lines of each (warm-up runs) left out."""
    runs = [json.loads(line) for f in files for line in f.read_text().splitlines()[skip:]
            if line.startswith("{")]
    lines = []
    by_case: dict[str, list[dict]] = {}
    for r in runs:
        name = r["case"] + (f" {r['chunk']}" if "chunk" in r else "") + (
            " pinned" if r.get("pinned") else "") + (
            f" autoreset {r['autoreset']}" if "autoreset" in r else "")
        by_case.setdefault(name, []).append(r)
    keys = ("wall_per_decision", "cpu_per_decision", "off_cpu_per_decision",
            "straggler_per_decision", "pipe_per_decision", "pipe_per_call",
            "cpu_straggler_per_decision", "workers_pipe_cpu_per_decision",
            "main_cpu_per_decision", "runq_in_step_per_decision",
            "runq_woken_per_decision", "same_cpu", "decisions_flown",
            "workers_cpu_per_decision", "machine_cores", "steal_cores")
    for case, rs in by_case.items():
        figures = ", ".join(f"{k} {statistics.median(r[k] for r in rs):.1f}"
                            for k in keys if k in rs[0])
        lines.append(f"{case} (n = {len(rs)}, load {min(r['load'] for r in rs):.1f}-"
                     f"{max(r['load'] for r in rs):.1f}): us, median: {figures}")
    names = list(by_case)
    pairs = [(a, b) for a in names for b in names if a != b and b in ("single", "procs")
             and not (a == "single" and b == "procs")]
    if len(names) == 2 and not pairs:  # two vectors: the first named against the second
        pairs = [tuple(names)]
    for a, b in (p for p in pairs if len(by_case[p[0]]) == len(by_case[p[1]])):
        scale = by_case[a][0]["workers"] if b == "single" else 1
        ratio = [scale * rb["wall_per_decision"] / ra["wall_per_decision"]
                 for ra, rb in zip(by_case[a], by_case[b], strict=True)]
        name = "speed-up over single" if b == "single" else f"speed / {b}"
        lines.append(f"{a}: {name}, run by run: median {statistics.median(ratio):.2f} "
                     f"({min(ratio):.2f}-{max(ratio):.2f})")
    return "\n".join(lines)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", choices=CASES)
    parser.add_argument("--episodes", type=int, default=5, help="episodes per worker")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk", type=int, default=200, help="decisions per worker call")
    parser.add_argument("--pin", action="store_true",
                        help="async: hold worker i to processor i (of those allowed)")
    parser.add_argument("--autoreset", choices=("NextStep", "SameStep"),
                        help="async: no resets of its own, the vector's autoreset mode, "
                        "episodes of unequal length, as many calls as N episodes of 20 s")
    parser.add_argument("--summarize", type=Path, nargs="+")
    parser.add_argument("--skip", type=int, default=1,
                        help="--summarize: first lines of each file left out (warm-up runs)")
    args = parser.parse_args()
    if args.summarize:
        print(summarize(args.summarize, args.skip))
        sys.exit(0)
    if args.case is None:
        parser.error("give a CASE or --summarize FILE")
    for name in ("episodes", "workers", "chunk"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1; got {getattr(args, name)}")
    print(json.dumps(run(args.case, args.episodes, args.workers, args.chunk, args.pin,
                         args.autoreset)))
