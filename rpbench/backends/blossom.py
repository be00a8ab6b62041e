"""Exact pairing by Blossom V (Kolmogorov 2009) as reimplemented in OGDF, for Oracle-1 and Oracle-2 at any scale.

OGDF's ``MatchingBlossomV`` (C++, GPL; the ``ogdf-wheel`` binaries) is a
minimum-cost *perfect* matching code, called through ``cppyy`` (a small C++
shim compiled once per process, ~3 s with loading OGDF).  A maximum-weight
matching is a perfect matching of the doubled graph: two copies of the
graph plus an edge ``v - v'`` per vertex, costing ``λ``.  In a perfect
matching both copies leave the same vertices exposed (each is matched to
its own copy), so one with ``M`` in each copy costs
``-2 (w(M) + λ |M|) + λ n``:

* ``λ = 0`` and pairs of value ``<= 0`` dropped: Oracle-1 (max ``w(M)``);
* ``λ > Σ|w|``: no loss of weight can pay for a lost pair, so the optimum is
  a maximum-weight matching among the maximum-cardinality ones — Oracle-2
  (docs/algorithms.md §4) in one exact solve, with integral costs throughout.

The pair count is checked against Edmonds' proven maximum
(:mod:`.cardinality`).  Blossom V cannot be interrupted: under a time limit
it runs in a forked child killed at the deadline (:mod:`._forked`), and
the best matching known (Edmonds' for Oracle-2, none for Oracle-1) is
returned as ``TIME_LIMIT``.  The assignment and trip packing are delegated
to the ``matching`` backend (``lap.lapmod``; HiGHS MIP).
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from rpbench.backends._common import Clock
from rpbench.backends._forked import Timeout, run_in_child
from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.cardinality import columns_of_mate, edge_indices, maximum_cardinality_matching
from rpbench.backends.highs import HighsBackend
from rpbench.backends.jv import lapmod_solution
from rpbench.exceptions import SolverError, SolverNotInstalledError
from rpbench.model import (
    AssignmentModel,
    Model,
    PairingModel,
    Solution,
    Status,
    Structure,
    TripPackingModel,
    empty_solution,
    make_solution,
)

#: OGDF multiplies integral costs by 4 internally; sums of costs must stay in int64.
INT64_SAFE = 2**60

_SHIM = r"""
#include <ogdf/graphalg/MatchingBlossomV.h>
#include <cstdint>
#include <unordered_set>
#include <vector>

// Minimum-cost perfect matching of (n, a, b, cost) into mate[]; false if none exists.
bool rpbench_blossom_v(int n, int m, const int32_t* a, const int32_t* b, const int64_t* cost, int32_t* mate) {
    ogdf::Graph G;
    std::vector<ogdf::node> V(n);
    for (int i = 0; i < n; ++i) V[i] = G.newNode();
    ogdf::EdgeArray<long long> W(G);
    for (int j = 0; j < m; ++j) W[G.newEdge(V[a[j]], V[b[j]])] = cost[j];
    ogdf::MatchingBlossomV<long long> solver;
    std::unordered_set<ogdf::edge> matching;
    if (!solver.minimumWeightPerfectMatching(G, W, matching)) return false;
    for (int i = 0; i < n; ++i) mate[i] = -1;
    for (ogdf::edge e : matching) {
        mate[e->source()->index()] = e->target()->index();
        mate[e->target()->index()] = e->source()->index();
    }
    return true;
}
"""


class BlossomBackend(Backend):
    name = "blossom"
    requires = ("cppyy", "ogdf_python", "ogdf_wheel", "lap", "highspy")
    exact = frozenset(Structure)
    description = (
        "OGDF's Blossom V (exact weighted matching, C++) for pairing at any scale; lap.lapmod for "
        "the assignment, HiGHS MIP for trip packing"
    )

    def solve(self, model: Model, options: SolveOptions) -> Solution:
        self.ensure_installed()
        if model.n_cols == 0:
            return empty_solution(model, self.name)
        if isinstance(model, AssignmentModel):
            return lapmod_solution(model, self.name)
        if isinstance(model, TripPackingModel):
            sol = HighsBackend().solve(model, options)
            note = "; ".join(m for m in ("trip packing solved by HiGHS (LP or MIP)", sol.message) if m)
            return replace(sol, backend=self.name, message=note)
        if model.n_cols == 0:
            return empty_solution(model, self.name)
        return blossom_v_pairing(model, options, Clock(), self.name)


@functools.cache
def _shim():
    """The compiled C++ entry point (loads OGDF into this process once)."""
    try:
        import cppyy
        from ogdf_python import ogdf  # noqa: F401  (loads libOGDF and its include paths)
    except Exception as exc:  # a broken install: one clear line, not a cling dump
        raise SolverNotInstalledError(
            f"backend 'blossom': OGDF could not be loaded through cppyy "
            f"({type(exc).__name__}: {exc}); reinstall with pip install "
            "'rpbench[blossom]' or choose another --solver"
        ) from None
    cppyy.cppdef(_SHIM)
    return cppyy.gbl.rpbench_blossom_v


def min_cost_perfect_matching(n: int, a: np.ndarray, b: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """``mate`` of a minimum-cost perfect matching of the graph ``(n, a, b)`` with integral ``cost``.

    Raises :class:`SolverError` if the graph has no perfect matching.
    """
    fn = _shim()
    mate = np.empty(n, np.int32)
    ok = fn(
        int(n),
        len(a),
        np.ascontiguousarray(a, np.int32),
        np.ascontiguousarray(b, np.int32),
        np.ascontiguousarray(cost, np.int64),
        mate,
    )
    if not ok:
        raise SolverError("Blossom V found no perfect matching")
    return mate


def blossom_v_matching(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, bonus: int = 0) -> np.ndarray:
    """Edge indices of a maximum-weight matching for integral weights ``w + bonus`` (doubled graph).

    Only vertices with an edge enter the doubled graph; ``bonus`` is the
    ``λ`` of the module docstring.
    """
    if len(a) == 0:
        return np.zeros(0, np.int64)
    used = np.unique(np.concatenate([a, b]))
    k = len(used)
    la, lb = np.searchsorted(used, a), np.searchsorted(used, b)
    cost = -(np.asarray(w, np.int64))
    if 4 * (2 * int(np.abs(cost).sum()) + k * int(bonus)) >= INT64_SAFE:
        raise SolverError(
            f"Blossom V: costs up to {int(np.abs(cost).max())} plus a pair bonus of {bonus} "
            "overflow 64-bit integers; build the model with a coarser unit_m"
        )
    own = np.arange(k)
    mate = min_cost_perfect_matching(
        2 * k,
        np.concatenate([la, la + k, own]),
        np.concatenate([lb, lb + k, own + k]),
        np.concatenate([cost, cost, np.full(k, int(bonus), np.int64)]),
    )
    first = mate[:k]
    v = np.flatnonzero((first >= 0) & (first < k) & (own < first))
    return edge_indices(n, a, b, used[v], used[first[v]])


def blossom_v_pairing(model: PairingModel, options: SolveOptions, clock: Clock, backend: str) -> Solution:
    """Oracle-1 or Oracle-2 by one Blossom V solve; ``TIME_LIMIT`` with the best known matching at the deadline."""
    lexi = model.objective == "cardinality_then_weight"
    with clock("build_s"):
        w = model.values.astype(np.int64)  # integral: the model validates it
        a, b = model.col_a.astype(np.int64), model.col_b.astype(np.int64)
        if lexi:
            top = maximum_cardinality_matching(model.n_orders, a, b)
            start, use, bonus = (
                columns_of_mate(model.n_orders, a, b, top.mate),
                np.arange(len(a)),
                int(np.abs(w).sum()) + 1,
            )
        else:
            start, use, bonus = np.zeros(0, np.int64), np.flatnonzero(w > 0), 0
        _shim()  # load OGDF before any fork: children inherit it
    limit = options.time_limit_s
    deadline = None if limit is None else clock.start + limit
    try:
        with clock("solve_s"):
            sel = use[
                run_in_child(
                    blossom_v_matching, (model.n_orders, a[use], b[use], w[use], bonus), deadline, solver="Blossom V"
                )
            ]
    except Timeout:
        chosen = start
        what = "Edmonds' maximum-cardinality matching" if lexi else "no pairs"
        return make_solution(
            model,
            chosen,
            Status.TIME_LIMIT,
            backend,
            message=f"Blossom V ran past the time limit; returning {what}",
            **clock.times,
        )
    if lexi and len(sel) != top.size:
        raise SolverError(f"Blossom V returned {len(sel)} pairs but the proven maximum is {top.size}")
    chosen = np.sort(sel)
    obj = model.objective_of(chosen)
    return make_solution(model, chosen, Status.OPTIMAL, backend, bound=obj, gap=0.0, **clock.times)
