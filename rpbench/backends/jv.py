"""Sparse Jonker-Volgenant (``lap.lapmod``) for the assignment (paper Eqs. 1-4, 16).

Used by the ``matching`` and ``blossom`` backends.  ``lap.lapmod`` treats
``LAP_LARGE = 1e6`` as infinity, so costs are scaled by a power of two (exact
in binary floating point) until every path length stays far below it.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from rpbench.backends._common import Clock
from rpbench.exceptions import SolverError
from rpbench.model import AssignmentModel, Solution, Status, make_solution

#: lap's "infinity"; costs are scaled so path lengths stay below LAP_SAFE.
LAP_LARGE = 1e6
LAP_SAFE = 2.0**18


def lapmod_solution(model: AssignmentModel, backend: str) -> Solution:
    """The optimal assignment as a :class:`Solution` (``INFEASIBLE`` when no assignment serves everyone)."""
    clock = Clock()
    chosen = lapmod_assignment(model, clock)
    if chosen is None:
        return make_solution(
            model,
            np.zeros(0, np.int64),
            Status.INFEASIBLE,
            backend,
            message="no assignment serves every passenger without a wait option",
            **clock.times,
        )
    obj = model.objective_of(chosen)
    return make_solution(model, chosen, Status.OPTIMAL, backend, bound=obj, gap=0.0, **clock.times)


def lapmod_assignment(model: AssignmentModel, clock: Clock) -> np.ndarray | None:
    """Optimal columns of an assignment model by ``lap.lapmod`` (``None`` if infeasible).

    Square construction, rows = passengers then one "idle" row per vehicle,
    columns = vehicles then one wait slot per passenger: passenger ``p`` may
    take vehicle ``v`` (cost ``-value``) or its own slot (its wait option);
    vehicle row ``v`` takes vehicle ``v`` (cost 0, unused) or the slot of
    any passenger that may ride ``v`` (cost 0, ``v`` serves that passenger).
    Perfect matchings correspond to assignments with equal cost, so the
    sparse matrix has ``2E + W + V`` entries instead of ``(P + V)²``.
    """
    import lap

    with clock("build_s"):
        P, V = model.n_passengers, model.n_vehicles
        cp, cv, val = model.col_passenger.astype(np.int64), model.col_vehicle.astype(np.int64), model.values
        ride = cv >= 0
        has_wait = np.zeros(P, bool)
        has_wait[cp[~ride]] = True
        if not has_wait.all() and not _serves_all(model, ~has_wait):
            return None
        N = P + V
        # per-passenger shift keeps costs >= 0 and leaves the argmin unchanged (every passenger row is matched once)
        top = np.full(P, -np.inf)
        np.maximum.at(top, cp, val)
        cost = top[cp] - val
        scale = _lap_scale(float(cost.max(initial=0.0)), N)
        rows = np.concatenate([cp, P + np.arange(V), P + cv[ride]])
        cols = np.concatenate([np.where(ride, cv, V + cp), np.arange(V), V + cp[ride]])
        cc = np.concatenate([cost * scale, np.zeros(V + int(ride.sum()))])
        col_id = np.concatenate([np.arange(model.n_cols), np.full(V + int(ride.sum()), -1)])
        key, order = _sorted_keys(rows * N + cols)
        cc, col_id = np.ascontiguousarray(cc[order]), col_id[order]
        ii = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=N))]).astype(np.int32)
        kk = (key % N).astype(np.int32)
    with clock("solve_s"):
        x, _ = lap.lapmod(N, cc, ii, kk, return_cost=False)
    with clock("extract_s"):
        want = np.arange(P, dtype=np.int64) * N + np.asarray(x[:P], dtype=np.int64)
        pos = np.searchsorted(key, want)
        pos = np.minimum(pos, len(key) - 1)
        if np.any(key[pos] != want) or np.any(col_id[pos] < 0):
            raise SolverError("lap.lapmod returned an assignment outside the sparse cost matrix")
        return np.sort(col_id[pos])


def _sorted_keys(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(sorted key, permutation)`` of unique non-negative int64 keys.

    Packs the position into the low bits and sorts values, not indices:
    several times faster than ``argsort`` on the 10^6 entries of a large round.
    """
    bits = max(1, int(len(key) - 1).bit_length())
    if int(key.max(initial=0)).bit_length() + bits > 62:
        order = np.argsort(key)
        return key[order], order
    packed = (key << bits) | np.arange(len(key), dtype=np.int64)
    packed.sort()
    return packed >> bits, packed & ((1 << bits) - 1)


def _serves_all(model: AssignmentModel, must: np.ndarray) -> bool:
    """Can every passenger in ``must`` (no wait option) get its own vehicle? (Hopcroft-Karp)"""
    from scipy.sparse.csgraph import maximum_bipartite_matching

    idx = np.flatnonzero(must)
    sel = (model.col_vehicle >= 0) & must[model.col_passenger]
    local = np.searchsorted(idx, model.col_passenger[sel])
    g = sp.csr_matrix((np.ones(int(sel.sum())), (local, model.col_vehicle[sel])), shape=(len(idx), model.n_vehicles))
    return bool(np.all(maximum_bipartite_matching(g, perm_type="column") >= 0))


def _lap_scale(max_cost: float, n: int) -> float:
    """A power of two bringing ``n * max_cost`` (a bound on any path length) below ``LAP_SAFE``."""
    if max_cost <= 0:
        return 1.0
    k = math.ceil(math.log2(n * max_cost / LAP_SAFE))
    return 2.0 ** -max(k, 0)


# --------------------------------------------------------------------- pairing
