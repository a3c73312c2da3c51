"""Run independent sweep tasks: in-process, on a local process pool, or on a Dask cluster.

Generic over the task function: ``fn(task) -> result`` must be a picklable top-level function and
``task`` a picklable object; the analytical task (:func:`femcheck.sweep.evaluate_analytical.run_analytical_task`)
is one, an FE task plugs in the same way. Results come back to the calling process one by one, in
completion order, through ``on_result(task, result)`` (the sweep writes each as a chunk there), so
an interruption loses only the tasks still running.

Back ends (:func:`run_tasks`):

- ``jobs = 0``: in this process, one task after the other (debugging, baseline of the overhead);
- ``jobs >= 1`` (default: the CPU count): a ``concurrent.futures.ProcessPoolExecutor`` with that many
  worker processes. Start method: ``fork`` where the platform has it (the workers inherit the imported
  modules and the loaded compiled kernel, so a pool starts in milliseconds instead of the ~3 s a
  ``spawn`` worker needs to import femcheck and load the kernel), else ``spawn``; the environment
  variable ``FEMCHECK_POOL_START`` (fork | forkserver | spawn) overrides it;
- ``scheduler = "tcp://host:port"`` (or the environment variable ``FEMCHECK_SCHEDULER``): the same
  tasks go to an existing Dask distributed cluster through ``distributed.Client.map``; its workers
  need femcheck installed. femcheck adds no scheduler of its own.
"""
from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import time
from collections.abc import Callable, Sequence

from femcheck.errors import FemcheckError

log = logging.getLogger(__name__)

SCHEDULER_ENV = "FEMCHECK_SCHEDULER"
START_METHOD_ENV = "FEMCHECK_POOL_START"


def pool_start_method() -> str:
    """Start method of the local pool: ``$FEMCHECK_POOL_START``, else fork if available, else spawn."""
    methods = multiprocessing.get_all_start_methods()
    wanted = os.environ.get(START_METHOD_ENV)
    if wanted:
        if wanted not in methods:
            raise FemcheckError(f"{START_METHOD_ENV}={wanted!r}: expected one of {methods}")
        return wanted
    return "fork" if "fork" in methods else "spawn"


class SweepInterrupted(FemcheckError):
    """A sweep stopped before all tasks finished; finished tasks are stored (``--resume`` continues)."""

    def __init__(self, message: str, done: int, total: int):
        self.done, self.total = done, total
        super().__init__(f"{message}; {done} of {total} tasks finished and stored; run again with --resume to finish")


def scheduler_address(scheduler: str | None) -> str | None:
    """The Dask scheduler address to use: the argument, else ``$FEMCHECK_SCHEDULER``, else None (local)."""
    address = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if address and "://" not in address:
        raise FemcheckError(f"--scheduler {address!r}: expected an address like tcp://host:8786")
    return address


def run_tasks(fn: Callable, tasks: Sequence, *, on_result: Callable, jobs: int | None = None,
              scheduler: str | None = None, on_progress: Callable | None = None) -> dict:
    """Run ``fn`` on every task; call ``on_result(task, result)`` in this process as each finishes.

    ``on_progress(done, total)`` is called after each stored result. Returns timing figures
    {"backend", "workers", "wall_s", "tasks"}. A failing task or a crashed worker stops the run
    (pending tasks are cancelled) and raises :class:`SweepInterrupted` after the finished ones are
    stored; Ctrl-C does the same and re-raises KeyboardInterrupt.
    """
    total = len(tasks)
    t0 = time.perf_counter()
    address = scheduler_address(scheduler)
    progress = on_progress or (lambda done, total: None)
    if total == 0:
        return {"backend": "none", "workers": 0, "wall_s": 0.0, "tasks": 0}
    if address:
        backend, workers = "dask", _run_dask(fn, tasks, address, on_result, progress)
    elif jobs == 0:
        backend, workers = "in-process", 1
        for done, task in enumerate(tasks, 1):
            try:
                result = fn(task)
            except Exception as exc:
                raise SweepInterrupted(f"task {done} failed: {type(exc).__name__}: {exc}", done - 1, total) from exc
            on_result(task, result)
            progress(done, total)
    else:
        backend, workers = "process-pool", _run_pool(fn, tasks, jobs or os.cpu_count() or 1, on_result, progress)
    wall = time.perf_counter() - t0
    log.info("%d tasks on %s (%d workers) in %.2f s", total, backend, workers, wall)
    return {"backend": backend, "workers": workers, "wall_s": wall, "tasks": total}


def _worker_init(parent_pid: int) -> None:
    """Pool worker set-up: Ctrl-C is the parent's to handle (it stops the workers), and a worker never
    outlives its parent (a killed ``femcheck sweep`` must not leave orphans computing)."""
    import signal
    import threading
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # Linux: the kernel sends SIGTERM when the parent dies
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch():  # elsewhere (and as a second guard): poll the parent
        while True:
            if os.getppid() != parent_pid:
                os._exit(1)
            time.sleep(1.0)
    threading.Thread(target=watch, daemon=True, name="femcheck-parent-watch").start()


def _stop_workers(pool) -> None:
    """Terminate the pool's processes now (Ctrl-C: do not wait minutes for running FE samples)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        if proc.is_alive():
            proc.terminate()


def _run_pool(fn, tasks, jobs, on_result, progress) -> int:
    workers = max(1, min(int(jobs), len(tasks)))
    total, done = len(tasks), 0
    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(pool_start_method()),
                                  initializer=_worker_init, initargs=(os.getpid(),))
    futures = {}
    interrupted = False
    try:
        futures = {pool.submit(fn, t): t for t in tasks}
        for fut in cf.as_completed(futures):
            try:
                result = fut.result()
            except Exception as exc:
                done += _store_finished(futures, on_result, skip=fut)
                what = f"a worker process died ({exc})" if isinstance(exc, cf.process.BrokenProcessPool) \
                    else f"a task failed: {type(exc).__name__}: {exc}"
                raise SweepInterrupted(what, done, total) from exc
            on_result(futures.pop(fut), result)
            done += 1
            progress(done, total)
    except KeyboardInterrupt:
        interrupted = True
        _stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=not interrupted, cancel_futures=True)
    return workers


def _run_dask(fn, tasks, address, on_result, progress) -> int:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a dependency
        raise FemcheckError(f"--scheduler needs dask[distributed]: {exc}") from None
    total, done = len(tasks), 0
    try:
        client = Client(address, timeout="20s", set_as_default=False)
    except OSError as exc:
        raise FemcheckError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    futures = []
    try:
        workers = len(client.scheduler_info(n_workers=-1).get("workers", {})) if _takes_n_workers(client) \
            else len(client.scheduler_info().get("workers", {}))
        futures = client.map(fn, list(tasks), pure=False)
        index = {f.key: t for f, t in zip(futures, tasks)}
        for fut in as_completed(futures, loop=client.loop):
            try:
                result = fut.result()
            except Exception as exc:
                done += _store_finished({f: index[f.key] for f in futures if f.key in index}, on_result, skip=fut)
                raise SweepInterrupted(f"a task failed on the cluster: {type(exc).__name__}: {exc}", done, total) from exc
            on_result(index.pop(fut.key), result)
            fut.release()
            done += 1
            progress(done, total)
    finally:
        if futures:
            client.cancel([f for f in futures if not f.done()])
        client.close()
    return workers


def _store_finished(futures: dict, on_result, skip) -> int:
    """Store every other future that finished successfully (called when one task failed); returns how many."""
    n = 0
    for fut, task in list(futures.items()):
        if fut is skip or not fut.done() or fut.cancelled():
            continue
        try:
            result = fut.result()
        except Exception:
            continue
        on_result(task, result)
        n += 1
    return n


def _takes_n_workers(client) -> bool:
    import inspect
    return "n_workers" in inspect.signature(client.scheduler_info).parameters
