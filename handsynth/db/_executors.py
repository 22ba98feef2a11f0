"""Executors of the database build: in-process, a local process pool, or Ray.

Each executor runs a picklable function over a list of tasks and yields
``(index, result)`` pairs as the tasks finish, in any order.  Workers pin
Mesa's llvmpipe to one rendering thread (``LP_NUM_THREADS=1``) before their
first render, so ``workers`` processes use ``workers`` cores.

Worker processes die with their parent: each watches its parent process
and exits within half a second once the parent is gone (killed with
SIGKILL, say), and they ignore Ctrl-C from their start, which the terminal sends to the
whole process group: the parent alone stops the run (and terminates its workers),
so an interrupt gives one message, not one traceback per worker.

Ray is imported here and nowhere else; it is an optional dependency (``pip
install handsynth[ray]``).  Without an address Ray starts a local instance
with ``num_cpus=workers``; with ``RAY_ADDRESS`` set (or ``ray.init`` already
called by the user) the tasks go to that cluster.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import TypeVar

from ..errors import DatabaseError, InvalidInputError

__all__ = ["EXECUTORS", "run_tasks"]

#: Names accepted by ``executor=``.
EXECUTORS: tuple[str, ...] = ("process", "ray")

_T = TypeVar("_T")  # a task
_R = TypeVar("_R")  # its result

#: Rendering threads per worker process.
_WORKER_ENV = {"LP_NUM_THREADS": "1"}


#: Seconds between a worker's checks that its parent is alive.
_PARENT_POLL_S = 0.5


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(_PARENT_POLL_S)
        if os.getppid() != parent:  # re-parented: the parent is gone
            os._exit(1)


def _init_worker(env: dict[str, str], parent: int) -> None:
    # Runs in the fresh (spawned) worker before any task, hence before the
    # first GL context is created.
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited already; also for other starts
    os.environ.update(env)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True,
                     name="handsynth-parent-watch").start()


@contextlib.contextmanager
def _children_ignore_sigint() -> Iterator[None]:
    """Start child processes that ignore Ctrl-C from their first instruction.

    An ignored SIGINT passes through fork and exec, and a Python interpreter
    that starts with SIGINT ignored leaves it so: a Ctrl-C while a worker is
    still importing cannot print a traceback there.  (A blocked signal mask
    would not do: the spawn start method clears it.)  The disposition is the
    whole process's, so a Ctrl-C in the milliseconds of this block is not
    seen here either; the block covers only the submissions that start
    workers.  Only the main thread may change signal handlers; elsewhere
    nothing is changed.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _terminate(pool: ProcessPoolExecutor) -> None:
    """Stop the pool's workers now (an interrupted or failed run)."""
    stop = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if stop is not None:
        stop()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


def _run_inline(fn: Callable[[_T], _R], tasks: Sequence[_T]) -> Iterator[tuple[int, _R]]:
    for i, task in enumerate(tasks):
        yield i, fn(task)


def _run_process(fn: Callable[[_T], _R], tasks: Sequence[_T],
                 workers: int) -> Iterator[tuple[int, _R]]:
    # "spawn": a worker must not inherit the parent's GL state or threads.
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                               initializer=_init_worker,
                               initargs=(dict(_WORKER_ENV), os.getpid()))
    # Keep at most 2 tasks per worker queued so that results stream back in
    # roughly the task order (bounded memory in the parent).
    pending: dict = {}
    next_task = 0
    finished = False
    try:
        while next_task < len(tasks) or pending:
            while next_task < len(tasks) and len(pending) < 2 * workers:
                # the first `workers` submissions start the worker processes
                starting = _children_ignore_sigint() if next_task < workers \
                    else contextlib.nullcontext()
                with starting:
                    pending[pool.submit(fn, tasks[next_task])] = next_task
                next_task += 1
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    raise DatabaseError(_broken_pool_message()) from None
                yield pending.pop(fut), result
        finished = True
    finally:
        if finished:
            pool.shutdown(wait=True)
        else:
            _terminate(pool)


def _broken_pool_message() -> str:
    main = sys.modules.get("__main__")
    script = getattr(main, "__file__", None)
    hint = ""
    if script and not getattr(main, "__spec__", None):  # run as `python script.py`
        hint = (f"; the workers import {os.path.basename(script)!r}: keep its work under "
                "`if __name__ == \"__main__\":`, or the workers run it again")
    return "a worker process of the build died before finishing its task" + hint


def _import_ray():
    try:
        import ray
    except ImportError:
        raise InvalidInputError(
            "executor='ray' needs the optional dependency Ray: pip install 'handsynth[ray]'"
        ) from None
    return ray


def _run_ray(fn: Callable[[_T], _R], tasks: Sequence[_T], workers: int) -> Iterator[tuple[int, _R]]:
    ray = _import_ray()
    started_here = False
    if not ray.is_initialized():
        kwargs = {"runtime_env": {"env_vars": dict(_WORKER_ENV)},
                  "include_dashboard": False, "log_to_driver": False}
        if not os.environ.get("RAY_ADDRESS"):
            kwargs["num_cpus"] = workers
        ray.init(**kwargs)
        started_here = True
    remote = ray.remote(num_cpus=1, max_retries=2)(fn)
    pending: dict = {}
    next_task = 0
    try:
        while next_task < len(tasks) or pending:
            while next_task < len(tasks) and len(pending) < 2 * workers:
                pending[remote.remote(tasks[next_task])] = next_task
                next_task += 1
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                yield pending.pop(ref), ray.get(ref)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if started_here:
            ray.shutdown()


def run_tasks(fn: Callable[[_T], _R], tasks: Sequence[_T], *, workers: int,
              executor: str = "process") -> Iterator[tuple[int, _R]]:
    """Run ``fn(task)`` for every task; yield ``(task index, result)`` as they finish.

    Parameters
    ----------
    fn : callable
        Module-level (picklable) function of one task.
    tasks : sequence
        Picklable task descriptions.
    workers : int, keyword-only
        Worker processes (Ray: CPUs of a local instance, or tasks in flight
        on an existing cluster).  With ``executor="process"`` and
        ``workers=1`` the tasks run in this process.
    executor : {"process", "ray"}, keyword-only

    Yields
    ------
    (int, object)
        Index into `tasks` and the value ``fn`` returned.
    """
    if executor not in EXECUTORS:
        raise InvalidInputError(
            f"executor must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    if executor == "ray":
        return _run_ray(fn, tasks, workers)
    if workers == 1:
        return _run_inline(fn, tasks)
    return _run_process(fn, tasks, workers)
