"""Run independent tasks (days, sweep points) in parallel on Dask.

The default is a Dask ``LocalCluster`` of worker *processes* on this machine
(one thread each: the solvers and numpy already use the core they get).
``scheduler="tcp://host:8786"`` submits to an existing Dask cluster instead,
for sweeps that outgrow one machine (workers need rpbench installed and the
data folder at the same path).  ``workers=1`` runs in-process, serially,
which is what tests use.  Results come back in task order.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Sequence

from rpbench.exceptions import ParameterError


def run_tasks(fn: Callable[[Any], Any], tasks: Sequence[Any], *, workers: int | None = None,
              scheduler: str | None = None, label: str = "tasks", progress: bool | None = None) -> list[Any]:
    """``[fn(t) for t in tasks]``, in parallel unless ``workers == 1``."""
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
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=40)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except OSError as exc:
            raise ParameterError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    try:
        futures = client.map(fn, list(tasks), pure=False)
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


def _bar(iterable, label: str, enabled: bool, total: int | None = None):
    if not enabled:
        return iterable
    from tqdm import tqdm
    return tqdm(iterable, total=total, desc=label, unit="run", file=sys.stderr, leave=False)
