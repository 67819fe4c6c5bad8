"""Run realizations: local worker processes (``concurrent.futures.ProcessPoolExecutor``)
or a Dask cluster (``dask.distributed.Client`` from an address or a scheduler file).

Both keep at most ``window`` realizations in flight (submitted as others finish, results
consumed as they complete) so that memory stays bounded however large n is; each finished
realization goes to ``on_result(index, rows)`` (the store) and to ``progress(done, total)``.
Local workers can write their realizations themselves (``store_in``); Dask workers, which
may not share this file system, send the rows back.
"""

from __future__ import annotations

import multiprocessing
import os
import select
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

from dask import distributed

from flightid.scenarios.montecarlo.store import write_realization
from flightid.scenarios.montecarlo.study import Study, run_realization

Rows = list[dict[str, Any]]
DASK_CONNECT_S = 5.0  # an unreachable scheduler is reported after this many s
OnResult = Callable[[int, Rows], None]
Progress = Callable[[int, int], None]
# one unit of work: task(description, index) -> rows, a module-level function of picklable
# arguments (a worker process or a Dask worker needs nothing else); default: a realization
Task = Callable[[Any, int], Rows]


def _report(progress: Progress | None, finished: int, total: int) -> None:
    if progress is not None:
        progress(finished, total)


def _run_and_store(description: Study, index: int, folder: str) -> None:
    """In a worker: one realization, written to the study's dataset by the worker itself
    (the Parquet write costs this process's CPU, which on a machine with one core per
    worker would be taken from the workers); no rows go back."""
    write_realization(folder, index, run_realization(description, index))


def _exit_with(parent: int) -> None:
    """In a worker: end this process as soon as the study's process ``parent`` ends
    (killed by SIGKILL, SIGTERM or SIGINT included), so that no worker outlives it; the
    forkserver and the resource tracker then end by themselves (their pipes close). A
    pidfd (Linux 5.3+) is waited on in a daemon thread; elsewhere the thread polls
    whether ``parent`` still exists every 0.5 s."""

    def watch() -> None:
        try:
            fd = os.pidfd_open(parent)
        except (AttributeError, OSError):
            fd = None
        if fd is not None:
            select.select([fd], [], [])
        else:
            while True:
                try:
                    os.kill(parent, 0)
                except ProcessLookupError:
                    break
                except PermissionError:
                    pass
                time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="flightid-parent-watch", daemon=True).start()


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's worker processes now (an interrupted study: a realization in
    flight is not waited for)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        if proc.is_alive():
            proc.terminate()
    pool.shutdown(wait=True, cancel_futures=True)


def run_local(description: Any, indices: Iterable[int], on_result: OnResult,
              workers: int | None = None, progress: Progress | None = None,
              window: int | None = None, store_in: str | Path | None = None,
              task: Task = run_realization) -> None:
    """Run the realizations ``indices`` in ``workers`` local processes (default: one per
    CPU). Workers start from a clean process (forkserver), never a fork of this one.
    ``store_in``: each worker writes its realizations to this study folder
    (``store.write_realization``) and ``on_result`` is not called (Monte Carlo studies
    only). ``task``: what each index runs (default ``run_realization`` of a ``Study``).

    Parameters
    ----------
    description : Any
        What ``task`` takes (a ``Study`` by default).
    indices : Iterable[int]
        Realization indices to run.
    on_result : OnResult
        ``on_result(index, rows)`` for each finished index.
    workers : int or None, optional
        Worker processes; None uses one per CPU.
    progress : Progress or None, optional
        ``progress(done, total)``.
    window : int or None, optional
        Indices in flight at a time; None uses twice ``workers``.
    store_in : str or Path or None, optional
        Study folder the workers write to.
    task : Task, optional
        ``task(description, index)`` -> rows.
    """
    todo = list(indices)
    workers = max(1, int(workers or os.cpu_count() or 1))
    window = max(1, int(window or 2 * workers))
    total, finished = len(todo), 0
    _report(progress, 0, total)
    if not todo:
        return
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    if context.get_start_method() == "forkserver":  # workers start with this module imported,
        context.set_forkserver_preload([__name__])  # so their parent watch starts at once

    def submit(index: int) -> Future:
        if store_in is not None:
            return pool.submit(_run_and_store, description, index, str(store_in))
        return pool.submit(task, description, index)

    with ProcessPoolExecutor(max_workers=min(workers, total), mp_context=context,
                             initializer=_exit_with, initargs=(os.getpid(),)) as pool:
        pending: dict[Future, int] = {}
        queue = iter(todo)
        try:
            for index in queue:
                pending[submit(index)] = index
                if len(pending) >= window:
                    break
            while pending:
                complete, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in complete:
                    index = pending.pop(fut)
                    rows = fut.result()  # a worker's error is raised here either way
                    if store_in is None:
                        on_result(index, rows)
                    finished += 1
                    _report(progress, finished, total)
                for index in queue:
                    pending[submit(index)] = index
                    if len(pending) >= window:
                        break
        except BaseException:
            for fut in pending:
                fut.cancel()
            _stop_workers(pool)
            raise


def dask_client(address: str | None = None, scheduler_file: str | None = None
                ) -> distributed.Client:
    """A client of the Dask scheduler at ``address`` (e.g. tcp://host:8786) or described
    by ``scheduler_file`` (as written by ``dask scheduler --scheduler-file``).

    Parameters
    ----------
    address : str or None, optional
        Scheduler address.
    scheduler_file : str or None, optional
        Scheduler file; give exactly one of the two.

    Returns
    -------
    distributed.Client
        The connected client.
    """
    if (address is None) == (scheduler_file is None):
        raise ValueError("give a Dask scheduler address or a scheduler file (one of them)")
    where = f"--dask-scheduler-file {scheduler_file}" if scheduler_file is not None \
        else f"--dask {address}"
    try:
        if scheduler_file is not None:
            if not Path(scheduler_file).is_file():
                raise FileNotFoundError(f"{scheduler_file}: no such Dask scheduler file")
            return distributed.Client(scheduler_file=str(scheduler_file),
                                      timeout=DASK_CONNECT_S)
        return distributed.Client(address, timeout=DASK_CONNECT_S)
    except FileNotFoundError:
        raise
    except OSError as exc:  # unreachable (refused, timed out, no such host)
        raise ValueError(f"{where}: no Dask scheduler answered within {DASK_CONNECT_S:g} s "
                         f"({exc})") from None
    except (ValueError, TypeError, KeyError) as exc:  # not an address, a damaged file
        raise ValueError(f"{where}: not a usable Dask scheduler address "
                         f"({type(exc).__name__}: {exc})") from None


def run_dask(description: Any, indices: Iterable[int], on_result: OnResult,
             client: distributed.Client, progress: Progress | None = None,
             window: int | None = None, task: Task = run_realization,
             key: str | None = None) -> None:
    """Run the realizations ``indices`` on the workers of a Dask ``client`` (flightid
    must be installed on them); at most ``window`` (default: twice the worker threads)
    are submitted at a time. ``task`` as for ``run_local``; ``key``: the prefix of the
    Dask task keys (default: from a ``Study``'s card).

    Parameters
    ----------
    description : Any
        What ``task`` takes (a ``Study`` by default).
    indices : Iterable[int]
        Realization indices to run.
    on_result : OnResult
        ``on_result(index, rows)`` for each finished index.
    client : distributed.Client
        The Dask client.
    progress : Progress or None, optional
        ``progress(done, total)``.
    window : int or None, optional
        Tasks submitted at a time.
    task : Task, optional
        ``task(description, index)`` -> rows.
    key : str or None, optional
        Prefix of the Dask task keys.
    """
    todo = list(indices)
    total, finished = len(todo), 0
    _report(progress, 0, total)
    if not todo:
        return
    if window is None:
        threads = sum(client.nthreads().values()) or 1
        window = 2 * threads
    window = max(1, int(window))
    queue = iter(todo)
    prefix = key or f"flightid-montecarlo-{description.identity()['card_sha256'][:12]}"

    def submit(index: int) -> distributed.Future:
        return client.submit(task, description, index, pure=False,
                             key=f"{prefix}-{index}-{os.getpid()}")

    first = []
    for index in queue:
        first.append(submit(index))
        if len(first) >= window:
            break
    indices_of = {f.key: i for f, i in zip(first, todo, strict=False)}
    completed = distributed.as_completed(first)
    try:
        for fut in completed:
            index = indices_of.pop(fut.key)
            on_result(index, fut.result())
            fut.release()
            finished += 1
            _report(progress, finished, total)
            nxt = next(queue, None)
            if nxt is not None:
                new = submit(nxt)
                indices_of[new.key] = nxt
                completed.add(new)
    except BaseException:
        completed.clear()
        raise
