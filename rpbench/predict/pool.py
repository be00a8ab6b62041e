"""Several predictions solved at once: a pool of worker processes, each solving whole chains of predictions.

The full day asks for 24 hourly predictions (one per hour's demand level and τ_0), each a fixed point on the
same cached structure (:mod:`.list_cache`).  Within one prediction the sweeps already share out their chunks
over numba's threads, but the work between sweeps (Anderson mixing, the per-state passes, the savings pass's
set-up, writing the cache entry) runs on one core; chains of predictions in separate processes keep every
core busy.  Each worker maps the same structure files read-only, so the page cache holds one copy for all.

The pool is started with ``spawn`` (the parent may hold numba's and solvers' threads, which ``fork`` would
copy in an unknown state), its workers share out the threads numba may use (``workers`` x threads <= what
numba sees) and die with their parent.  A prediction's values do not depend on where, or on how many
threads, it was solved (the sweeps' partial sums are cut and added in a fixed order,
:mod:`.fixed_point`), and a chain's warm starts are fixed by the chain, so the pool returns exactly what
solving the chains one after another returns.
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

import numpy as np
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


#: A job: predictions solved one after another in one process, each warm-started from the one before it.
Chain = Sequence[tuple[OdRates, PredictConfig]]


def solve_predictions(
    network: RoadNetwork, params: Params, chains: Sequence[Chain], workers: int | None = None
) -> list[Prediction]:
    """The lean prediction (per-OD values only, :func:`.prediction.predict` with ``lean``) of each
    ``(rates, config)`` of the ``chains``, solved and cached, in order (the chains' predictions one after
    another).

    A chain's predictions are solved in turn, each warm-started from the ρ of the one before it when their OD
    sets are the same (only the demand level or τ_0 moved: fewer sweeps to the same fixed point, within the
    tolerance); chains are independent of each other.  ``workers``: processes solving chains at once (default:
    the cores, ``os.cpu_count()``; never more than the chains); 1 solves them here, one after another, with the
    same values.
    """
    if workers is not None and workers < 1:
        raise ValueError(f"workers = {workers} must be >= 1")
    n = min(len(chains), workers or os.cpu_count() or 1)
    if multiprocessing.current_process().daemon:  # a daemonic worker (a Dask worker's) may not start processes
        n = 1
    if n <= 1:
        return [p for chain in chains for p in solve_chain(network, params, chain)]
    threads = max(1, get_num_threads() // n)
    # The chains carry the network without its distance table (hundreds of MB; each worker reads it from the
    # disk cache).  They go through the pool's queue, not with the worker's start: a worker that dies starting
    # (a script that runs itself again, unguarded by `if __name__ == "__main__"`) is then an error, where a
    # start payload larger than a pipe's buffer would leave this process waiting for it forever.
    bare = dataclasses.replace(network, _index={})
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(n, mp_context=context, initializer=_start_worker, initargs=(threads,))
    try:
        results = list(pool.map(_solve, [(bare, params, chain) for chain in chains]))
    except BaseException:
        _stop(pool)
        raise
    pool.shutdown(wait=True)
    return [p for solved in results for p in solved]


def solve_chain(network: RoadNetwork, params: Params, chain: Chain) -> list[Prediction]:
    """The chain's lean predictions in turn, each warm-started from the previous one's ρ when it was solved
    here on the same OD set (a prediction found in the cache has no ρ: the next one starts from ρ = 0)."""
    out: list[Prediction] = []
    previous: Prediction | None = None
    for rates, config in chain:
        rho0 = None
        if previous is not None and len(previous.rho) and _same_ods(previous.rates, rates):
            rho0 = previous.rho
        previous = predict(network, rates, params, config, lean=True, rho0=rho0)
        out.append(dataclasses.replace(previous, rho=np.zeros(0)))  # what a dispatcher reads: per-OD values
    return out


def _same_ods(a: OdRates, b: OdRates) -> bool:
    return len(a) == len(b) and np.array_equal(a.origin, b.origin) and np.array_equal(a.destination, b.destination)


def _start_worker(threads: int) -> None:
    """Worker initializer: die with the parent, leave Ctrl-C to it, take its share of the threads."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.suppress(OSError, AttributeError):  # not Linux: the parent stops its workers itself
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    set_num_threads(threads)


def _solve(job: tuple[RoadNetwork, Params, Chain]) -> list[Prediction]:
    network, params, chain = job
    return solve_chain(_networks.setdefault(network.content_hash, network), params, chain)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Stop the workers now (an error or Ctrl-C in the parent): queued jobs dropped, running ones killed."""
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        process.kill()
    pool.shutdown(wait=True, cancel_futures=True)
