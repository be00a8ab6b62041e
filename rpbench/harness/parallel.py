"""Run independent tasks (days, sweep points) in parallel.

The default is a pool of worker *processes* on this machine
(:class:`concurrent.futures.ProcessPoolExecutor`, started with ``spawn``:
the parent holds solver and numba threads, which ``fork`` would copy in an
unknown state).  ``scheduler="tcp://host:8786"`` submits to an existing Dask
cluster instead, for sweeps that outgrow one machine (the optional ``dask``
extra; workers need rpbench installed and the data folder at the same path).
``workers=1`` runs in-process, serially, which is what tests use.  Results
come back in task order.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from rpbench.exceptions import ParameterError


def run_tasks(
    fn: Callable[[Any], Any],
    tasks: Sequence[Any],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    label: str = "tasks",
    progress: bool | None = None,
) -> list[Any]:
    """``[fn(t) for t in tasks]``, in parallel unless ``workers == 1``.

    ``fn`` and the tasks must pickle (``fn`` a module-level function; a task
    carries everything it needs, its run specification included).  An exception in a task, or in this
    process (Ctrl-C, SIGTERM turned into an exception by the CLI), stops the
    workers before it propagates, so the caller's results-folder cleanup does
    not race with workers still writing into it.
    """
    if workers is not None and workers < 1:
        raise ParameterError(f"--workers {workers} must be >= 1")
    n = len(tasks)
    if n == 0:
        return []
    if progress is None:
        progress = sys.stderr.isatty()
    if scheduler is not None:
        return _on_dask(fn, tasks, scheduler, label, progress)
    if workers == 1 or n == 1:
        return [fn(t) for t in _bar(tasks, label, progress)]
    return _in_processes(fn, tasks, min(n, workers or os.cpu_count() or 1), label, progress)


def _in_processes(
    job: Callable[[Any], Any], tasks: Sequence[Any], n_workers: int, label: str, progress: bool
) -> list[Any]:
    """The tasks on a local pool of ``n_workers`` processes; the first failure stops the rest."""
    pool = ProcessPoolExecutor(n_workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [pool.submit(job, t) for t in tasks]
        for future in _bar(as_completed(futures), label, progress, total=len(futures)):
            future.result()  # re-raises a task's exception (BrokenProcessPool if a worker died)
        results = [f.result() for f in futures]
    except BaseException:
        _terminate(pool)
        raise
    pool.shutdown(wait=True)
    return results


def _terminate(pool: ProcessPoolExecutor) -> None:
    """Stop the pool at once: queued tasks are cancelled and running ones' workers terminated."""
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        terminate()
        return
    # Before 3.14 the executor has no public way to stop a running task; its process table is the only
    # handle (read before shutdown, which drops it).
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join()


def _on_dask(job: Callable[[Any], Any], tasks: Sequence[Any], scheduler: str, label: str, progress: bool) -> list[Any]:
    """The tasks on an existing Dask cluster (``--scheduler ADDRESS``)."""
    try:
        from dask.distributed import Client
        from dask.distributed import as_completed as dask_completed
    except ImportError:
        raise ParameterError("--scheduler needs Dask, which is not installed: pip install 'rpbench[dask]'") from None
    try:
        client = Client(scheduler, timeout="10s")
    except OSError as exc:
        raise ParameterError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    try:
        futures = client.map(job, list(tasks), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        out: list[Any] = [None] * len(futures)
        for future in _bar(dask_completed(futures), label, progress, total=len(futures)):
            out[index[future.key]] = future.result()
        return out
    finally:
        client.close()


def _bar(iterable, label: str, enabled: bool, total: int | None = None):
    if not enabled:
        return iterable
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc=label, unit="run", file=sys.stderr, leave=False)
