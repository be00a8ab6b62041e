"""The fastest exact special-purpose algorithms for rpbench's structures.

* **Assignment** (paper Eqs. 1-4, 16): sparse Jonker-Volgenant, ``lap.lapmod``
  (:mod:`.jv`).
* **Pairing** (docs/algorithms.md §4): maximum-weight general matching by
  PyMatching's sparse blossom through the reduction to a minimum-weight
  T-join — :func:`max_weight_matching`; Oracle-2 by Edmonds' exact maximum
  cardinality (:mod:`.cardinality`) and then a Lagrangian bonus per pair —
  :func:`max_weight_max_cardinality`.  What PyMatching cannot prove (and
  Oracle-2 beyond ``BLOSSOM_V_FIRST`` pairs) goes to OGDF's Blossom V
  (:mod:`.blossom`) when the ``blossom`` extra is installed, else to the
  HiGHS MIP.
* **Trip packing** (docs/algorithms.md §3.3): no special-purpose algorithm; it is
  delegated to the HiGHS MIP (exact), and the solution's message says so.

Exactness.  Both libraries compute with sentinels or discretised weights,
so the inputs are shaped to keep them exact:

* PyMatching leaves edge weights unscaled only when *every* weight is
  integral and none exceeds ``2**24 - 1`` (``NUM_DISTINCT_WEIGHTS - 1`` in
  ``user_graph.cc``; otherwise it multiplies by ``(2**24 - 1) / max|w|`` and
  rounds, or refuses).  Values are divided by their greatest common divisor
  (exact) and the reduction's integral costs are checked against that limit
  before every call.  Beyond it — e.g. savings over ~8 km in millimetres —
  the matching of coarsened values warm-starts the exact HiGHS MIP
  (``[options.extra] overflow = "error"`` raises instead).
* ``lap.lapmod`` treats ``LARGE = 1e6`` as infinity, so costs are scaled by a
  power of two (exact in binary floating point) until every path length
  stays far below it.

Time limits.  Sparse blossom cannot be interrupted: under a time limit a
PyMatching solve of a large graph runs in a forked child that is killed at
its deadline, and the HiGHS MIP takes over from the best matching so far.
``lapmod`` is polynomial and fast; it has no time limit.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from rpbench.backends._common import Clock
from rpbench.backends._forked import Timeout, run_in_child
from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.blossom import BlossomBackend, blossom_v_pairing
from rpbench.backends.cardinality import columns_of_mate, edge_indices, mate_of, maximum_cardinality_matching
from rpbench.backends.highs import HighsBackend
from rpbench.backends.jv import lapmod_solution
from rpbench.exceptions import SolverError
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

#: Largest edge weight PyMatching accepts and keeps unscaled when all weights are integral.
PM_MAX_WEIGHT = 2**24 - 1
#: Pairings with fewer candidate pairs are solved in-process even under a time limit.
SMALL_GRAPH = 5_000
#: Oracle-2 pairings with this many candidate pairs go straight to Blossom V when it is installed:
#: sparse blossom needs a pair bonus near the value spread to reach k*, and slows down by orders
#: of magnitude there (full haikou-day, 465k pairs: > 15 min; the 2017-05-01 peak, 12k: 0.4 s).
BLOSSOM_V_FIRST = 100_000


class MatchingBackend(Backend):
    name = "matching"
    requires = ("lap", "pymatching", "highspy")
    exact = frozenset(Structure)
    description = (
        "lap.lapmod (sparse Jonker-Volgenant) for the assignment, PyMatching sparse blossom for "
        "pairing; trip packing delegated to the HiGHS MIP"
    )

    def solve(self, model: Model, options: SolveOptions) -> Solution:
        self.ensure_installed()
        if model.n_cols == 0:
            return empty_solution(model, self.name)
        if isinstance(model, TripPackingModel):
            sol = HighsBackend().solve(model, options)
            note = "; ".join(m for m in ("trip packing solved by HiGHS (LP or MIP)", sol.message) if m)
            return replace(sol, backend=self.name, message=note)
        if isinstance(model, AssignmentModel):
            return lapmod_solution(model, self.name)
        return solve_pairing(model, options, Clock(), self.name)


class RangeExceeded(Exception):
    """The reduction's integral costs would exceed PM_MAX_WEIGHT."""

    def __init__(self, needed: int):
        super().__init__(needed)
        self.needed = needed


def reduction_costs(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integral (pair costs, boundary costs) of the T-join reduction for weights ``w >= 1``.

    Vertex ``v`` gets a boundary edge of cost ``β_v = ⌊(t1_v + t2_v) / 2⌋ + 1``
    (``t1, t2`` its two largest incident weights, 0 if missing) and pair
    ``(u, v)`` costs ``β_u + β_v - w_uv > 0``.  A T-join (every vertex of odd
    degree) made of a matching ``M`` plus boundary edges costs ``Σβ - w(M)``.
    A vertex ``v`` of degree >= 3 has two pair edges ``(v, x), (v, y)``;
    trading them for the boundary edges of ``x`` and ``y`` changes the cost by
    ``w_vx + w_vy - 2β_v < 0``, so every optimal T-join is a matching — a
    maximum-weight one.  Per-vertex β keep the costs (hence PyMatching's
    exact range) as small as this argument allows.
    """
    ends = np.concatenate([a, b])
    ww = np.concatenate([w, w])
    # the two largest incident weights in O(E), without sorting: t2 is t1 again where t1 occurs twice
    t1 = np.zeros(n, ww.dtype)
    np.maximum.at(t1, ends, ww)
    top = ww == t1[ends]
    t2 = np.zeros(n, ww.dtype)
    np.maximum.at(t2, ends[~top], ww[~top])
    t2 = np.where(np.bincount(ends[top], minlength=n) > 1, t1, t2)
    beta = (t1 + t2) // 2 + 1
    return beta[a] + beta[b] - w, beta


def max_weight_matching(
    n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, clock: Clock, deadline: float | None = None
) -> np.ndarray:
    """Indices of a maximum-weight matching for integral weights ``w >= 1``, by PyMatching.

    Every vertex is a detection event; see :func:`reduction_costs` for why
    the minimum-weight T-join PyMatching finds is a maximum-weight matching.
    Raises :class:`RangeExceeded` when a cost would exceed ``PM_MAX_WEIGHT``
    and :class:`Timeout` when ``deadline`` (a ``time.perf_counter`` value)
    passes first: sparse blossom cannot be interrupted, so a solve with a
    deadline runs in a forked child process that is killed then.
    """
    E = len(a)
    if E == 0:
        return np.zeros(0, np.int64)
    with clock("build_s"):
        pair_cost, beta = reduction_costs(n, a, b, w.astype(np.int64))
        needed = int(max(pair_cost.max(), beta.max()))
        if needed > PM_MAX_WEIGHT:
            raise RangeExceeded(needed)
    t0 = time.perf_counter()
    # small graphs finish in milliseconds: forking (~10 ms) to enforce the deadline would dominate
    guard = deadline if E >= SMALL_GRAPH else None
    pairs, build_s, _ = _in_child(_pymatching_pairs, (n, a, b, pair_cost, beta), guard)
    clock.times["build_s"] += build_s
    clock.times["solve_s"] += time.perf_counter() - t0 - build_s  # includes the fork, if any
    with clock("extract_s"):
        pairs = pairs[pairs[:, 1] >= 0]
        return edge_indices(n, a, b, pairs[:, 0], pairs[:, 1])


def _pymatching_pairs(n, a, b, pair_cost, beta) -> tuple[np.ndarray, float, float]:
    """PyMatching's matched detection-event pairs (``-1`` = boundary), with build and solve times."""
    import pymatching

    t0 = time.perf_counter()
    E = len(a)
    indptr = np.concatenate([np.arange(0, 2 * E + 1, 2), 2 * E + np.arange(1, n + 1)])
    indices = np.concatenate([np.column_stack([a, b]).ravel(), np.arange(n)])
    H = sp.csc_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(n, E + n))
    matching = pymatching.Matching()
    matching.load_from_check_matrix(
        H,
        weights=np.concatenate([pair_cost, beta]).astype(np.float64),
        faults_matrix=sp.csc_matrix((0, E + n), dtype=np.uint8),
        use_virtual_boundary_node=True,
    )
    t1 = time.perf_counter()
    pairs = matching.decode_to_matched_dets_array(np.ones(n, dtype=np.uint8))
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2), t1 - t0, time.perf_counter() - t1


def _in_child(fn, args, deadline: float | None):
    """``fn(*args)`` under ``deadline`` (:func:`._forked.run_in_child`), PyMatching imported before any fork."""
    if deadline is not None:
        import pymatching  # noqa: F401  (imported once here, inherited by every child)
    return run_in_child(fn, args, deadline, solver="PyMatching")


def max_weight_max_cardinality(
    n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, clock: Clock, deadline: float | None = None
) -> tuple[np.ndarray, bool, int | None]:
    """A maximum-weight matching among the maximum-cardinality ones (Oracle-2), whether it is proven, and a bound.

    ``k*`` comes first, exactly, from Edmonds' algorithm with its Tutte-Berge
    certificate (:mod:`.cardinality`).  With a bonus ``λ`` per pair, a
    maximum-weight matching for ``w + λ`` that has ``k*`` pairs beats every
    other ``k*``-matching by weight (all get the same ``k*·λ``), so it is
    exact.  λ starts at a quarter of the value spread and doubles up to 4 x
    the spread: larger bonuses make the costs nearly uniform, and sparse
    blossom then slows down by orders of magnitude (it is built for sparse
    defects; here every vertex is one).  Unproven, the heaviest matching found
    is augmented to ``k*`` pairs (Edmonds again) and returned as a warm start,
    with the best Lagrangian bound: ``M_λ`` is a maximum-weight matching for
    ``w + λ``, so every ``k*``-matching weighs at most
    ``w(M_λ) + λ (|M_λ| - k*)``.  On :class:`Timeout` the matching and the
    bound ride on the exception (``best``, ``bound``).
    """
    with clock("build_s"):
        top = maximum_cardinality_matching(n, a, b)
    if top.size == 0:
        return np.zeros(0, np.int64), True, 0
    best, bound = columns_of_mate(n, a, b, top.mate), None
    spread = int(w.max()) - int(w.min()) + 1
    lam = max(1, spread // 4)
    while lam <= 4 * spread:
        wl = w + lam
        keep = np.flatnonzero(wl > 0)  # a pair worth <= 0 never helps a maximum-weight matching
        try:
            sel = keep[max_weight_matching(n, a[keep], b[keep], wl[keep], clock, deadline)]
        except Timeout as exc:
            exc.best, exc.bound = best, bound
            raise
        if len(sel) == top.size:
            return sel, True, int(w[sel].sum())
        lagrangian = int(w[sel].sum()) + lam * (len(sel) - top.size)
        bound = lagrangian if bound is None else min(bound, lagrangian)
        with clock("build_s"):  # the heaviest start so far, completed to k* pairs
            best = columns_of_mate(
                n, a, b, maximum_cardinality_matching(n, a, b, start=mate_of(n, a[sel], b[sel])).mate
            )
        lam *= 2
    return best, False, bound


def solve_pairing(model: PairingModel, options: SolveOptions, clock: Clock, backend: str) -> Solution:
    """PyMatching when it can prove the optimum, else Blossom V, else the HiGHS MIP warm-started from its best matching.

    With a time limit, PyMatching gets half of it for Oracle-2 (the rest is
    left to a fallback) and all of it for Oracle-1.
    """
    overflow = options.extra.get("overflow", "fallback")
    if overflow not in ("fallback", "error"):
        raise SolverError(f'backend {backend!r}: [options.extra] overflow = {overflow!r}; use "fallback" or "error"')
    lexi = model.objective == "cardinality_then_weight"
    if lexi and model.n_cols >= BLOSSOM_V_FIRST and _blossom_installed():
        return _blossom_v(model, options, clock, backend, f"{model.n_cols} candidate pairs")
    limit = options.time_limit_s
    deadline = None if limit is None else clock.start + (limit / 2 if lexi else limit)
    with clock("build_s"):
        v = model.values.astype(np.int64)
        a, b = model.col_a.astype(np.int64), model.col_b.astype(np.int64)
        g = int(np.gcd.reduce(np.abs(v))) if np.any(v) else 1
        w = v // g  # exact: every value is a multiple of g
    step, why, sel, proven, bound = 1, "", np.zeros(0, np.int64), False, None
    while True:  # step > 1: coarsened, only to warm-start the fallback
        wc = w if step == 1 else np.round(w / step).astype(np.int64)
        try:
            if lexi:
                sel, proven, bound = max_weight_max_cardinality(model.n_orders, a, b, wc, clock, deadline)
            else:
                use = np.flatnonzero(wc > 0)  # Oracle-1: a pair worth <= 0 never helps
                sel, proven = use[max_weight_matching(model.n_orders, a[use], b[use], wc[use], clock, deadline)], True
            break
        except RangeExceeded as exc:
            if overflow == "error":
                raise SolverError(_overflow_message(model, backend, g, exc.needed, lexi)) from None
            why = why or f"values exceed PyMatching's exact range (reduction costs up to {exc.needed})"
            if _blossom_installed():  # exact in int64: no coarsened warm start needed
                return _blossom_v(model, options, clock, backend, why)
            step *= 2
        except Timeout as exc:
            sel = exc.best if exc.best is not None else sel
            why, bound = why or "PyMatching ran out of its share of the time limit", exc.bound
            break
    chosen = np.sort(sel)
    if step == 1 and proven and not why:
        obj = model.objective_of(chosen)
        return make_solution(model, chosen, Status.OPTIMAL, backend, bound=obj, gap=0.0, **clock.times)
    why = why or "no pair bonus up to 4x the value spread reached the proven maximum number of pairs"
    if _blossom_installed():
        return _blossom_v(model, options, clock, backend, why)
    # a bound on coarsened values says nothing exact about the model's
    lagrangian = bound * g if bound is not None and step == 1 else None
    return _highs_fallback(model, options, clock, backend, chosen, why, lagrangian)


def _blossom_installed() -> bool:
    """Is the ``blossom`` extra (OGDF, cppyy) installed?"""
    return BlossomBackend.is_installed()


def _blossom_v(model: PairingModel, options: SolveOptions, clock: Clock, backend: str, why: str) -> Solution:
    """The exact Blossom V route (:mod:`.blossom`), within what is left of the time limit."""
    sol = blossom_v_pairing(model, options, clock, backend)
    note = "; ".join(m for m in (f"{why}: solved by OGDF's Blossom V", sol.message) if m)
    return replace(sol, message=note)


def _highs_fallback(
    model: PairingModel,
    options: SolveOptions,
    clock: Clock,
    backend: str,
    start: np.ndarray,
    why: str,
    lagrangian: int | None = None,
) -> Solution:
    """The exact HiGHS MIP (two stages for Oracle-2), warm-started with ``start``; honest status on a time limit.

    ``lagrangian`` (Oracle-2) is a proven bound from the pair-bonus runs; the
    tighter of it and HiGHS's bound is reported, and proves the optimum if
    the incumbent reaches it.
    """
    hint = np.zeros(model.n_cols)
    hint[start] = 1.0
    limit = clock.remaining(options.time_limit_s)
    sol = HighsBackend().solve(model, replace(options, time_limit_s=limit), hint=hint)
    times = {k: clock.times[k] + getattr(sol, k) for k in clock.times}
    note = "; ".join(m for m in (f"{why}: solved by the HiGHS MIP warm-started from PyMatching", sol.message) if m)
    sol = replace(sol, backend=backend, message=note, **times)
    if sol.status is Status.OPTIMAL or lagrangian is None or (sol.bound is not None and sol.bound <= lagrangian):
        return sol
    obj = sol.objective
    if lagrangian < obj + 1:  # integral values: nothing better exists
        return replace(
            sol, status=Status.OPTIMAL, bound=obj, gap=0.0, message=f"{note}; proven by the Lagrangian bound"
        )
    return replace(
        sol,
        bound=float(lagrangian),
        gap=(lagrangian - obj) / max(1.0, abs(obj)),
        message=f"{note}; bound from the pair-bonus (Lagrangian) relaxation",
    )


def _overflow_message(model: PairingModel, backend: str, g: int, needed: int, lexi: bool) -> str:
    factor = 2 ** math.ceil(math.log2(needed / PM_MAX_WEIGHT))
    what = "values plus the cardinality bonus" if lexi else "values"
    return (
        f"backend {backend!r}: the {what} of {model.name!r} (up to {int(np.abs(model.values).max())} x "
        f"{model.unit_m:g} m) need reduction costs up to {needed} > {PM_MAX_WEIGHT}, PyMatching's exact integer "
        f"range; build the model with unit_m >= {model.unit_m * g * factor:g} m, or drop [options.extra] "
        'overflow = "error" to fall back to the HiGHS MIP'
    )
