"""Run independent tasks (days, sweep points) in parallel.

The default is a pool of worker *processes* on this machine
(:class:`concurrent.futures.ProcessPoolExecutor`, started with ``spawn``:
the parent holds solver and numba threads, which ``fork`` would copy in an
unknown state).  ``scheduler="tcp://host:8786"`` submits to an existing Dask
cluster instead, for sweeps that outgrow one machine (the optional ``dask``
extra; workers need rpbench installed and the data folder at the same path).
``workers=1`` runs in-process, serially, which is what tests use.  Results
come back in task order.

Local workers die with their parent, even when it is killed with SIGKILL
(on Linux the kernel's parent-death signal, elsewhere a thread polling the
parent's PID), and ignore Ctrl-C, which the terminal sends to the whole
process group: the parent stops them itself.  A worker that dies while
running a task (a signal, the out-of-memory killer) stops the others and
is one :class:`WorkerDiedError` naming the task and the signal.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import reprlib
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from rpbench.exceptions import ParameterError, RpbenchError

#: prctl(2) option: the signal the kernel sends this process when the thread that created it exits.
_PR_SET_PDEATHSIG = 1
#: How often a worker without prctl (not Linux) looks whether its parent is still there.
_PARENT_POLL_S = 1.0

#: In a worker process: slot i holds the PID of the worker running task i, or minus it once the task
#: ended (shared memory written before the task starts, so it survives the worker's SIGKILL).
_running: Any = None


class WorkerDiedError(RpbenchError, RuntimeError):
    """A worker process died while running a task (killed by a signal, the out-of-memory killer)."""


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
    not race with workers still writing into it.  A task is named in errors by the last part of its
    ``out`` folder when it has one (a day, a sweep point).
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
    context = multiprocessing.get_context("spawn")
    running = context.RawArray("q", len(tasks))
    pool = ProcessPoolExecutor(
        n_workers, mp_context=context, initializer=_start_worker, initargs=(os.getpid(), running)
    )
    processes: dict[int, Any] = {}
    try:
        futures = [pool.submit(_run_one, job, i, t) for i, t in enumerate(tasks)]
        # submit wakes the pool's manager thread *before* it spawns a worker, so the manager may wait without
        # the last worker's sentinel and miss its death until another worker ends: wake it once all are up
        wakeup = getattr(pool, "_executor_manager_thread_wakeup", None)
        if wakeup is not None:
            wakeup.wakeup()
        processes = dict(getattr(pool, "_processes", None) or {})  # all spawned by now: read before shutdown
        for future in _bar(as_completed(futures), label, progress, total=len(futures)):
            future.result()  # re-raises a task's exception (BrokenProcessPool if a worker died)
        results = [f.result() for f in futures]
    except BrokenProcessPool:
        processes.update(getattr(pool, "_processes", None) or {})
        _terminate(pool)
        raise WorkerDiedError(_death_line(label, tasks, list(running), processes)) from None
    except BaseException:
        _terminate(pool)
        raise
    pool.shutdown(wait=True)
    return results


def _start_worker(parent: int, running: Any) -> None:
    """Worker initializer: die with the parent, leave Ctrl-C to it, record which task runs where."""
    global _running
    _running = running
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if not _kernel_kills_with(parent):
        threading.Thread(target=_watch_parent, args=(parent,), name="rpbench-parent-watch", daemon=True).start()


def _kernel_kills_with(parent: int) -> bool:
    """Ask Linux for SIGKILL when the parent dies (prctl PR_SET_PDEATHSIG); False where that is not possible.

    The signal comes when the parent *thread* that spawned this worker exits: run_tasks spawns from the
    thread that waits for the results, so the two end together."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0:
            return False
    except (OSError, AttributeError):
        return False
    if os.getppid() != parent:  # the parent died before prctl: no signal will come
        os.kill(os.getpid(), signal.SIGKILL)
    return True


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(_PARENT_POLL_S)
    os.kill(os.getpid(), signal.SIGKILL)


def _run_one(job: Callable[[Any], Any], index: int, task: Any) -> Any:
    """In a worker: ``job(task)``, with ``task``'s slot of the shared table saying that this process runs it."""
    if _running is not None:
        _running[index] = os.getpid()
    try:
        return job(task)
    finally:
        if _running is not None:
            _running[index] = -os.getpid()


def _death_line(label: str, tasks: Sequence[Any], running: list[int], processes: dict[int, Any]) -> str:
    """Which worker died of what, running which task.  The pool SIGTERMs the other workers once one died,
    so a death by another signal (or an exit status) is the cause; only SIGTERM deaths leave it ambiguous."""
    exits = {pid: p.exitcode for pid, p in processes.items() if p.exitcode not in (None, 0)}
    causes = {pid: code for pid, code in exits.items() if code != -signal.SIGTERM} or exits
    if not causes:
        return f"{label}: a worker process died (the process pool broke); the other workers were stopped"
    code = next(iter(causes.values()))
    how = f"was killed by {_signal_name(-code)}" if code < 0 else f"exited with status {code}"
    names = [_task_name(tasks[i]) for i, pid in enumerate(running) if pid in causes]
    pids = ", ".join(str(pid) for pid in causes)
    if not names:
        return f"{label}: a worker process (pid {pids}) {how}; the other workers were stopped"
    return (
        f"{label}: the worker process running {' or '.join(names)} {how} (pid {pids}); the other workers were stopped"
    )


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


def _task_name(task: Any) -> str:
    out = getattr(task, "out", None)
    if isinstance(out, (str, os.PathLike)):
        return Path(out).name
    return reprlib.repr(task)


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
