"""Run independent tasks (days, sweep points) in parallel on Dask.

The default is a Dask ``LocalCluster`` of worker *processes* on this machine
(one thread each: the solvers and numpy already use the core they get).
``scheduler="tcp://host:8786"`` submits to an existing Dask cluster instead,
for sweeps that outgrow one machine (workers need rpbench installed and the
data folder at the same path).  ``workers=1`` runs in-process, serially,
which is what tests use.  Results come back in task order.
"""

from __future__ import annotations

import logging
import os
import sys
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from rpbench.exceptions import ParameterError
from rpbench.harness.strict import is_strict, strict_mode


def run_tasks(fn: Callable[[Any], Any], tasks: Sequence[Any], *, workers: int | None = None,
              scheduler: str | None = None, label: str = "tasks", progress: bool | None = None) -> list[Any]:
    """``[fn(t) for t in tasks]``, in parallel unless ``workers == 1``.

    Worker processes run ``fn`` under the caller's ``--strict`` policy (:mod:`rpbench.harness.strict`).
    An exception in a task, or in this process (Ctrl-C, SIGTERM turned into an exception by the CLI),
    closes the client and a local cluster (its workers stop) before it propagates, so the caller's
    results-folder cleanup does not race with workers still writing into it.
    """
    if workers is not None and workers < 1:
        raise ParameterError(f"--workers {workers} must be >= 1")
    n = len(tasks)
    if n == 0:
        return []
    if progress is None:
        progress = sys.stderr.isatty()
    if scheduler is None and (workers == 1 or n == 1):
        return [fn(t) for t in _bar(tasks, label, progress)]
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        n_workers = min(n, workers or os.cpu_count() or 1)
        # CRITICAL: a failing task is reported once, as the caller's one-line error, not also as the
        # workers' logged traceback on stderr
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except OSError as exc:
            raise ParameterError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    try:
        futures = client.map(_UnderPolicy(fn, is_strict()), list(tasks), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        out: list[Any] = [None] * n
        done = as_completed(futures)
        for future in _bar(done, label, progress, total=n):
            out[index[future.key]] = future.result()
        return out
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@dataclass(frozen=True)
class _UnderPolicy:
    """``fn`` run in a worker under the strict-mode policy of the process that submitted it (picklable)."""

    fn: Callable[[Any], Any]
    strict: bool

    def __call__(self, task: Any) -> Any:
        with strict_mode(self.strict):
            return self.fn(task)


def _bar(iterable, label: str, enabled: bool, total: int | None = None):
    if not enabled:
        return iterable
    from tqdm import tqdm
    return tqdm(iterable, total=total, desc=label, unit="run", file=sys.stderr, leave=False)
