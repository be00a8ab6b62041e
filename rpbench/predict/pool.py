"""Several predictions solved at once: a pool of worker processes, each solving whole predictions.

The full day asks for 24 hourly predictions (one per hour's demand level and τ_0), each an independent fixed
point on the same cached structure (:mod:`.list_cache`).  Within one prediction the sweeps already share out
their chunks over numba's threads, but the work between sweeps (Anderson mixing, the per-state passes, the
savings pass's set-up, writing the cache entry) runs on one core; whole predictions in separate processes
keep every core busy.  Each worker maps the same structure files read-only, so the page cache holds one copy
for all of them.

The pool is started with ``spawn`` (the parent may hold numba's and solvers' threads, which ``fork`` would
copy in an unknown state), its workers share out the threads numba may use (``workers`` x threads <= what
numba sees) and die with their parent.  A prediction's values do not depend on where, or on how many
threads, it was solved (the sweeps' partial sums are cut and added in a fixed order,
:mod:`.fixed_point`), so the pool returns exactly what solving the jobs one after another returns.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import multiprocessing
import os
import signal
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor

from numba import get_num_threads, set_num_threads

from rpbench.network import RoadNetwork
from rpbench.predict.config import PredictConfig
from rpbench.predict.prediction import Prediction, predict
from rpbench.predict.rates import OdRates
from rpbench.scenarios.base import Params

#: prctl(2) option: the signal the kernel sends this process when its parent's thread exits (Linux).
_PR_SET_PDEATHSIG = 1

#: In a worker: the networks its jobs came with, by content hash, so that their distance table is read once.
_networks: dict[str, RoadNetwork] = {}


def solve_predictions(
    network: RoadNetwork, params: Params, jobs: Sequence[tuple[OdRates, PredictConfig]], workers: int | None = None
) -> list[Prediction]:
    """The lean prediction (per-OD values only, :func:`.prediction.predict` with ``lean``) of each
    ``(rates, config)`` job, solved and cached, in job order.

    ``workers``: processes solving predictions at once (default: the cores, ``os.cpu_count()``; never more
    than the jobs); 1 solves them here, one after another.
    """
    if workers is not None and workers < 1:
        raise ValueError(f"workers = {workers} must be >= 1")
    n = min(len(jobs), workers or os.cpu_count() or 1)
    if multiprocessing.current_process().daemon:  # a daemonic worker (a Dask worker's) may not start processes
        n = 1
    if n <= 1:
        return [predict(network, rates, params, config, lean=True) for rates, config in jobs]
    threads = max(1, get_num_threads() // n)
    # The jobs carry the network without its distance table (hundreds of MB; each worker reads it from the disk
    # cache).  They go through the pool's queue, not with the worker's start: a worker that dies starting (a
    # script that runs itself again, unguarded by `if __name__ == "__main__"`) is then an error, where a start
    # payload larger than a pipe's buffer would leave this process waiting for it forever.
    bare = dataclasses.replace(network, _index={})
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(n, mp_context=context, initializer=_start_worker, initargs=(threads,))
    try:
        results = list(pool.map(_solve, [(bare, params, rates, config) for rates, config in jobs]))
    except BaseException:
        _stop(pool)
        raise
    pool.shutdown(wait=True)
    return results


def _start_worker(threads: int) -> None:
    """Worker initializer: die with the parent, leave Ctrl-C to it, take its share of the threads."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.suppress(OSError, AttributeError):  # not Linux: the parent stops its workers itself
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    set_num_threads(threads)


def _solve(job: tuple[RoadNetwork, Params, OdRates, PredictConfig]) -> Prediction:
    network, params, rates, config = job
    network = _networks.setdefault(network.content_hash, network)
    return predict(network, rates, params, config, lean=True)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Stop the workers now (an error or Ctrl-C in the parent): queued jobs dropped, running ones killed."""
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        process.kill()
    pool.shutdown(wait=True, cancel_futures=True)
