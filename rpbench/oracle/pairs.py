"""Candidate pairs of the offline oracle: which two orders may share, and at what saving.

Pair feasibility of docs/algorithms.md §4.2 (A18).  Let ``i`` be the earlier order
(``t_i <= t_j``, ties by order id) and ``dt = t_j - t_i``:

* waiting pair, ``dt <= K̄`` (inclusive): j requests while i still waits, so
  the vehicle picks i up and drives ``o_i -> o_j`` directly:
  ``POOL(A=i, B=j, h=o_i, δ=0, pre=0)`` (§1.1, the paper's Eqs. 5-6);
* ``both_pickup_orders``: j may also be picked up first,
  ``POOL(A=j, B=i, h=o_j)``; the orientation with the larger saving wins
  (tie -> i first);
* ``allow_enroute``: i starts riding at ``t_i + K̄`` (the most favourable
  time for a clairvoyant planner) and at ``t_j`` is at arc length
  ``s = v (dt - K̄)`` along its shortest path ``P_i``; when ``0 < s < l_i``
  the vehicle turns at the next node ``h`` of ``P_i`` at or after ``s``:
  ``POOL(A=i, B=j, h, δ = l(o_i, h), pre = δ - s)``.  Waiting and en-route
  pairs are disjoint (``dt <= K̄`` versus ``dt > K̄``).

With ``window = "bound"`` the pairs are those of the proven upper bound
(docs/bound.md): every pair rpbench's simulator can form, with the largest
saving it can realise.  With A picked up first, B can only join while A is
assigned and not yet dropped off, so ``t_B - t_A`` lies in
``[-K_B, K_A + (R̄ + l_A)/v]`` with each order's own patience ``K_p``; the
vehicle then turns towards ``o_B`` at a node ``h`` of A's shortest path
``P_A`` with ``l(h, o_B) <= R̄``, no further along than it can have driven
by ``t_B + K_B`` and no earlier than it must have driven by ``t_B`` (A is
picked up by ``t_A + K_A + R̄/v`` at the latest and then drives on: at least
``v (t_B - t_A - K_A) - R̄`` along ``P_A``).  The earliest such node ``h*`` is
the best place to turn (the pooled route only grows along ``P_A``), so the
weight is ``POOL(A, B, h*, δ = l(o_A, h*))`` with no further pick-up test;
both pick-up orders, the larger saving wins.

Detours must be ``<= D̄`` (``order_rule`` as in §1.1, default min over the
feasible service orders).  The pick-up distance ``pk = pre + l(h, o_B)`` is
tested against R̄ only with ``pickup_check`` (O3: the authors' oracle never
tested it).  The weight is the saving ``e = l_A + l_B - L`` (Eq. 5).

Enumeration is vectorised: orders sorted by (time, id), each order's window
of later partners found by ``searchsorted``, and all (i, j) pairs of a block
of consecutive ``i`` generated and evaluated as flat numpy arrays, in blocks
of bounded size -- never a Python loop per pair.  An exact necessary test on
A's detour (two distance look-ups) discards most pairs before the full POOL.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields, replace

import numpy as np
import pandas as pd

from rpbench.exceptions import ParameterError
from rpbench.geometry import ORDER_RULES, PoolResult, choose_order, pair_geometry
from rpbench.network import Distances
from rpbench.scenarios.base import Orders, Params

#: Pairs evaluated per numpy block (bounds memory to a few hundred MB).
BLOCK_PAIRS = 1 << 21
#: Time windows of a pair: the paper's (requests within K̄) or the upper bound's.
WINDOWS = ("patience", "bound")


@dataclass(frozen=True)
class PairRules:
    """The pair-feasibility rules of §4.2 (defaults = the authors' oracle, A18)."""

    planner_patience_s: float = 90.0  # K̄
    max_detour_m: float = 3000.0  # D̄
    max_pickup_m: float = 3000.0  # R̄ (only used with pickup_check)
    speed_mps: float = 30.0 / 3.6  # v (only used with allow_enroute)
    both_pickup_orders: bool = False  # oracle_both_pickup_orders
    pickup_check: bool = False  # oracle_pickup_check
    allow_enroute: bool = False  # oracle_allow_enroute
    order_rule: str = "min_feasible"
    window: str = "patience"  # "patience": §4.2's K̄; "bound": the upper bound's (docs/bound.md)

    def __post_init__(self) -> None:
        for name in ("planner_patience_s", "max_detour_m", "max_pickup_m", "speed_mps"):
            value = getattr(self, name)
            if not isinstance(value, (int, float, np.integer, np.floating)) or not np.isfinite(value) or value < 0:
                raise ParameterError(f"oracle rule {name} = {value!r} must be a finite number >= 0")
        if self.speed_mps <= 0:
            raise ParameterError(f"oracle rule speed_mps = {self.speed_mps!r} must be > 0")
        if self.order_rule not in ORDER_RULES:
            raise ParameterError(f"order_rule {self.order_rule!r} unknown; expected one of {', '.join(ORDER_RULES)}")
        if self.window not in WINDOWS:
            raise ParameterError(f"pair window {self.window!r} unknown; expected one of {', '.join(WINDOWS)}")
        if self.window == "bound" and (
            self.pickup_check or self.allow_enroute or not self.both_pickup_orders or self.order_rule != "min_feasible"
        ):
            raise ParameterError(
                "the upper bound's pairs take both pick-up orders, no pick-up test, no en-route "
                "geometry and the best feasible service order: its rules cannot be changed"
            )

    @classmethod
    def from_params(cls, params: Params, **flags) -> PairRules:
        """K̄, D̄, R̄ and v from a scenario's parameters, plus the flags."""
        return cls(
            planner_patience_s=params.planner_patience_s,
            max_detour_m=params.max_detour_m,
            max_pickup_m=params.max_pickup_m,
            speed_mps=params.speed_mps,
            **flags,
        )

    def replace(self, **changes) -> PairRules:
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True, eq=False)
class CandidatePairs:
    """Feasible pairs, one row per unordered pair of orders (arrays of equal length).

    ``first``/``second`` are row positions in the scenario's ``Orders``: the
    order picked up first (POOL's ``A``) and the joining one (``B``).  Rows are
    sorted by ``(min(first, second), max(first, second))``.
    """

    n_orders: int
    first: np.ndarray  # int64
    second: np.ndarray  # int64
    enroute: np.ndarray  # bool: B joins while A rides (allow_enroute)
    fofo: np.ndarray  # bool: A dropped first
    saving_m: np.ndarray  # e = l_A + l_B - L
    length_m: np.ndarray  # L, from A's origin
    detour_first_m: np.ndarray
    detour_second_m: np.ndarray
    shared_m: np.ndarray
    pickup_m: np.ndarray  # pk = pre + l(h, o_B)
    rules: PairRules
    evaluated: int = 0  # pairs inside the time windows, tested with POOL
    seconds: float = 0.0
    stats: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.first)

    @property
    def low(self) -> np.ndarray:
        return np.minimum(self.first, self.second)

    @property
    def high(self) -> np.ndarray:
        return np.maximum(self.first, self.second)

    def take(self, rows) -> CandidatePairs:
        """The subset of rows ``rows`` (indices or a boolean mask)."""
        pick = {
            f.name: getattr(self, f.name)[rows] for f in fields(self) if isinstance(getattr(self, f.name), np.ndarray)
        }
        return replace(self, **pick)

    def to_frame(self, orders: Orders) -> pd.DataFrame:
        """One row per pair, with order ids, request times and the POOL result."""
        return pd.DataFrame(
            {
                "first_id": orders.order_id[self.first],
                "second_id": orders.order_id[self.second],
                "first_request_s": orders.request_s[self.first],
                "second_request_s": orders.request_s[self.second],
                "service_order": np.where(self.fofo, "FOFO", "FOLO"),
                "enroute": self.enroute,
                "saving_m": self.saving_m,
                "length_m": self.length_m,
                "detour_first_m": self.detour_first_m,
                "detour_second_m": self.detour_second_m,
                "shared_m": self.shared_m,
                "pickup_m": self.pickup_m,
            }
        )


def find_candidates(
    distances: Distances | np.ndarray, orders: Orders, rules: PairRules, *, block_pairs: int = BLOCK_PAIRS
) -> CandidatePairs:
    """All feasible pairs of ``orders`` under ``rules`` (docs/algorithms.md §4.2).

    ``distances`` is the network's one distance oracle (its shortest paths
    are the paths vehicles drive, needed by ``allow_enroute``); a bare
    all-pairs matrix is accepted when ``allow_enroute`` is off.
    """
    t0 = time.perf_counter()
    oracle = distances if isinstance(distances, Distances) else None
    if oracle is None and rules.allow_enroute:
        raise ParameterError(
            "allow_enroute needs the orders' shortest paths: pass the network's "
            "Distances (network.distances()), not a bare distance matrix"
        )
    # a plain view: gathers from a memmap subclass are slower
    dist = np.asarray(distances.dist if isinstance(distances, Distances) else distances)
    if block_pairs < 1:
        raise ParameterError(f"block_pairs = {block_pairs!r} must be >= 1")
    n = len(orders)
    rank = np.lexsort((orders.order_id, orders.request_s))  # (time, id) order
    t = orders.request_s[rank]
    o = orders.origin[rank].astype(np.intp)
    d = orders.destination[rank].astype(np.intp)
    solo = dist[o, d]
    if rules.window == "bound":
        if oracle is None:
            raise ParameterError(
                "the upper bound needs the orders' shortest paths: pass the network's "
                "Distances (network.distances()), not a bare distance matrix"
            )
        return _bound_candidates(oracle, dist, orders, rules, rank, t, o, d, solo, block_pairs, t0)
    k_bar = float(rules.planner_patience_s)

    # Window of each i: j in (i, hi_i).  The bound is widened by a hair and the
    # exact tests below (dt <= K̄; 0 < s < l_i) decide, so rounding in t_i + K̄
    # can never drop a pair that the exact test accepts.
    reach = k_bar + (solo / rules.speed_mps if rules.allow_enroute else 0.0)
    hi = np.searchsorted(t, t + reach + 1e-6 * (1.0 + np.abs(t) + reach), side="right")
    count = np.maximum(hi - np.arange(n) - 1, 0)

    path = _paths(oracle, dist, o, d) if oracle is not None and rules.allow_enroute and n else None
    parts: list[dict] = []
    evaluated = 0
    for ii, jj in _pair_blocks(count, block_pairs):
        evaluated += len(ii)
        dt = t[jj] - t[ii]
        waiting = dt <= k_bar
        parts.append(_waiting_pairs(dist, o, d, solo, ii[waiting], jj[waiting], rules))
        if path is not None:
            s = rules.speed_mps * (dt - k_bar)
            moving = ~waiting & (s > 0) & (s < solo[ii])
            parts.append(_enroute_pairs(dist, o, d, solo, ii[moving], jj[moving], s[moving], path, rules))
    cand = _assemble(parts, rank, n, rules, evaluated, t0)
    return replace(cand, stats={"waiting": int((~cand.enroute).sum()), "enroute": int(cand.enroute.sum())})


def _paths(distances: Distances, dist, o, d):
    """``(offsets, nodes, cum)``: every order's shortest path and ``l(o_i, k-th node of P_i)`` along it."""
    offsets, nodes = distances.paths_batch(o, d)
    return (np.asarray(offsets, np.int64), np.asarray(nodes, np.intp), dist[np.repeat(o, np.diff(offsets)), nodes])


def _pair_blocks(count: np.ndarray, block_pairs: int):
    """``(ii, jj)`` arrays of the (earlier, later) pairs inside the windows, about ``block_pairs`` at a time;
    order ``i``'s window holds the ``count[i]`` orders after it (by time)."""
    for i0, i1 in _blocks(count, block_pairs):
        ii = np.repeat(np.arange(i0, i1), count[i0:i1])
        if not len(ii):
            continue
        starts = np.cumsum(count[i0:i1]) - count[i0:i1]
        yield ii, ii + 1 + np.arange(len(ii)) - np.repeat(starts, count[i0:i1])


def _assemble(parts: list[dict], rank, n: int, rules: PairRules, evaluated: int, t0: float) -> CandidatePairs:
    """The evaluated blocks as one CandidatePairs, in scenario row positions and a canonical row order."""
    cols = {k: np.concatenate([p[k] for p in parts]) if parts else np.zeros(0, dtype) for k, dtype in _COLUMNS.items()}
    first, second = rank[cols.pop("first")].astype(np.int64), rank[cols.pop("second")].astype(np.int64)
    srt = np.lexsort((np.maximum(first, second), np.minimum(first, second)))
    return CandidatePairs(
        n_orders=n,
        first=first[srt],
        second=second[srt],
        enroute=cols["enroute"][srt],
        fofo=cols["fofo"][srt],
        saving_m=cols["saving_m"][srt],
        length_m=cols["length_m"][srt],
        detour_first_m=cols["detour_first_m"][srt],
        detour_second_m=cols["detour_second_m"][srt],
        shared_m=cols["shared_m"][srt],
        pickup_m=cols["pickup_m"][srt],
        rules=rules,
        evaluated=int(evaluated),
        seconds=time.perf_counter() - t0,
    )


def bound_rules(params: Params) -> PairRules:
    """The pair rules of the proven upper bound on a scenario with ``params`` (docs/bound.md)."""
    return PairRules.from_params(params, both_pickup_orders=True, window="bound")


def _bound_candidates(
    distances: Distances, dist, orders: Orders, rules: PairRules, rank, t, o, d, solo, block_pairs: int, t0: float
) -> CandidatePairs:
    """Every pair the simulator can form, weighted by the largest saving it can realise (docs/bound.md)."""
    n = len(orders)
    patience = orders.patience_s[rank]
    path = _paths(distances, dist, o, d) if n else (np.zeros(1, np.int64), np.zeros(0, np.intp), np.zeros(0))
    # i (earlier) first: j requests before i's drop-off, at most t_i + K_i + (R̄ + l_i)/v; j first: i still
    # waits, t_j <= t_i + K_i.  Widened by the simulator's tolerances (1e-9 s on patience, TOLERANCE_M on R̄)
    # and a hair for rounding: a wider window only adds candidate pairs, it never drops one.
    reach = patience + (rules.max_pickup_m + 1e-6 + solo) / rules.speed_mps + 1e-6
    hi = np.searchsorted(t, t + reach + 1e-9 * (1.0 + np.abs(t)), side="right")
    count = np.maximum(hi - np.arange(n) - 1, 0)
    parts: list[dict] = []
    evaluated = 0
    for ii, jj in _pair_blocks(count, block_pairs):
        evaluated += len(ii)
        reverse_ok = t[jj] - t[ii] <= patience[ii] + 1e-6
        # how far along its path the first passenger's vehicle can be while the second still waits
        reach_f = rules.speed_mps * (t[jj] + patience[jj] - t[ii]) + 1e-6
        reach_r = rules.speed_mps * (t[ii] + patience[ii] - t[jj]) + 1e-6
        # and how far it must be once the second is revealed (the first picked up by t_A + K_A + R̄/v)
        floor_f = least_driven_m(t[jj] - t[ii], patience[ii], rules)
        floor_r = least_driven_m(t[ii] - t[jj], patience[jj], rules)
        turn = (path, reach_f, reach_r, floor_f, floor_r)
        parts.append(_best_orientation(dist, o, d, solo, ii, jj, reverse_ok, rules, turn=turn))
    return replace(_assemble(parts, rank, n, rules, evaluated, t0), stats={"window": "bound"})


def least_driven_m(gap_s: np.ndarray, patience_a_s: np.ndarray, rules: PairRules) -> np.ndarray:
    """How far along P_A the first passenger A's vehicle has driven, at least, in any round B can join
    (``gap_s = t_B - t_A``; docs/bound.md, F5): A is assigned by ``t_A + K_A`` a vehicle at most R̄ away,
    picked up by ``t_A + K_A + R̄/v`` and then driven on at the set speed, and B joins no earlier than
    ``t_B``.  Negative when B can join before A's pick-up (no limit).  Lowered by the simulator's
    tolerances and a hair for rounding: a lower limit only ever admits more turning nodes."""
    v = rules.speed_mps
    return v * (gap_s - patience_a_s - 2e-6) - (rules.max_pickup_m + 2e-6)


def _best_orientation(dist, o, d, solo, ii, jj, reverse_ok, rules: PairRules, turn=None) -> dict:
    """POOL(A=i, B=j, h=o_i) and, where ``reverse_ok``, POOL(A=j, B=i, h=o_j): the larger saving (tie: i first).

    ``turn = (path, reach_f, reach_r, floor_f, floor_r)``: the upper bound's geometry instead of
    h = o_A: the vehicle turns at the first node of A's path within R̄ of o_B, between the least and the
    most A's vehicle can have driven (:func:`_turn_at_first_reachable_node`).
    """
    rev_idx = np.flatnonzero(reverse_ok)
    if turn is None:
        rows_f, fwd = _pool_where_possible(dist, o, d, solo, ii, jj, rules)
        rows_r, rev = _pool_where_possible(dist, o, d, solo, jj[rev_idx], ii[rev_idx], rules)
    else:
        path, reach_f, reach_r, floor_f, floor_r = turn
        rows_f, fwd = _turn_at_first_reachable_node(dist, o, d, solo, ii, jj, reach_f, floor_f, path, rules)
        rows_r, rev = _turn_at_first_reachable_node(
            dist, o, d, solo, jj[rev_idx], ii[rev_idx], reach_r[rev_idx], floor_r[rev_idx], path, rules
        )
    rows_r = rev_idx[rows_r]
    best_f = np.full(len(ii), -np.inf)
    best_f[rows_f] = fwd.saving
    flip = np.zeros(len(ii), dtype=bool)
    flip[rows_r] = rev.saving > best_f[rows_r]
    keep_f, keep_r = ~flip[rows_f], flip[rows_r]
    fwd = PoolResult(*(getattr(fwd, f.name)[keep_f] for f in fields(PoolResult)))
    rev = PoolResult(*(getattr(rev, f.name)[keep_r] for f in fields(PoolResult)))
    return _concat(
        _rows(ii[rows_f[keep_f]], jj[rows_f[keep_f]], False, fwd),
        _rows(jj[rows_r[keep_r]], ii[rows_r[keep_r]], False, rev),
    )


_COLUMNS = {
    "first": np.int64,
    "second": np.int64,
    "enroute": bool,
    "fofo": bool,
    "saving_m": np.float64,
    "length_m": np.float64,
    "detour_first_m": np.float64,
    "detour_second_m": np.float64,
    "shared_m": np.float64,
    "pickup_m": np.float64,
}


def _blocks(count: np.ndarray, block_pairs: int):
    """Consecutive ranges [i0, i1) of first orders holding about ``block_pairs`` pairs each."""
    n = len(count)
    if n == 0:
        return
    cum = np.cumsum(count)
    i0 = 0
    while i0 < n:
        base = cum[i0 - 1] if i0 else 0
        i1 = int(np.searchsorted(cum, base + block_pairs, side="right"))
        i1 = max(i1, i0 + 1)  # one order with a huge window still forms a block
        yield i0, min(i1, n)
        i0 = i1


def _pickup_limit(rules: PairRules) -> float:
    return rules.max_pickup_m if rules.pickup_check else np.inf


def _pool_where_possible(dist, o, d, solo, a, b, rules: PairRules, h=None, delta=None, pre=None):
    """POOL(A=a, B=b, h, δ, pre) on the pairs that pass a cheap necessary test.

    Returns ``(rows, PoolResult)`` for the feasible pairs only (``rows`` index
    the input arrays).  The test is exact, not a heuristic: in both service
    orders A's ride is at least ``δ + l(h, o_B) + l(o_B, d_A)`` (FOLO's
    ``l_B + l(d_B, d_A) >= l(o_B, d_A)`` by the triangle inequality), so a pair
    with ``δ + l(h, o_B) + l(o_B, d_A) - l_A > D̄`` is infeasible.  It costs two
    distance look-ups instead of four and rejects about three quarters of the
    pairs inside the time window on the Haikou data.
    """
    h = o[a] if h is None else h
    delta = np.zeros(len(a)) if delta is None else delta
    pre = np.zeros(len(a)) if pre is None else pre
    bound = delta + dist[h, o[b]] + dist[o[b], d[a]] - solo[a]
    # The slack absorbs float rounding in the triangle inequality of computed distances.
    rows = np.flatnonzero(bound <= rules.max_detour_m + 1e-6 * (1.0 + np.abs(bound)))
    a, b = a[rows], b[rows]
    g = pair_geometry(
        dist, o[a], d[a], solo[a], o[b], d[b], solo[b], h[rows], delta[rows], pre[rows], rules.max_detour_m
    )
    r = choose_order(g, _pickup_limit(rules), rules.order_rule)
    ok = r.feasible
    return rows[ok], PoolResult(*(getattr(r, f.name)[ok] for f in fields(PoolResult)))


def _turn_at_first_reachable_node(dist, o, d, solo, a, b, reach_m, floor_m, path, rules: PairRules):
    """POOL(A=a, B=b) with the vehicle turning at h*, the first node of P_A at arc length ``>= floor_m``
    with ``l(h, o_B) <= R̄`` whose predecessor on P_A lies within ``reach_m`` of o_A (docs/bound.md);
    ``(rows, PoolResult)`` of the feasible pairs.

    Feasibility at h = o_A is necessary (the pooled route and A's detour only
    grow along P_A), so only the pairs that pass it are walked along their
    paths, from the first node at or beyond ``floor_m``, one vectorised step per node.
    """
    offsets, nodes, cum = path
    rows, at_origin = _pool_where_possible(dist, o, d, solo, a, b, rules)
    start = _first_node_at_or_beyond(offsets, cum, a[rows], floor_m[rows])
    from_origin = start == offsets[a[rows]]
    near = from_origin & (dist[o[a[rows]], o[b[rows]]] <= rules.max_pickup_m + 1e-6)
    keep = [(rows[near], PoolResult(*(getattr(at_origin, f.name)[near] for f in fields(PoolResult))))]
    walk = rows[~near]
    if len(walk):
        pos = start[~near] + from_origin[~near]  # o_A itself failed the pick-up test
        end = offsets[a[walk] + 1]
        h = np.full(len(walk), -1, dtype=np.intp)
        active = np.flatnonzero(pos < end)
        while len(active):
            p = pos[active]
            in_reach = cum[p - 1] <= reach_m[walk[active]]
            hit = in_reach & (dist[nodes[p], o[b[walk[active]]]] <= rules.max_pickup_m + 1e-6)
            h[active[hit]] = p[hit]
            go = in_reach & ~hit & (p + 1 < end[active])
            pos[active[go]] += 1
            active = active[go]
        found = h >= 0
        w, hp = walk[found], h[found]
        if len(w):
            g = pair_geometry(
                dist,
                o[a[w]],
                d[a[w]],
                solo[a[w]],
                o[b[w]],
                d[b[w]],
                solo[b[w]],
                nodes[hp],
                cum[hp],
                np.zeros(len(w)),
                rules.max_detour_m,
            )
            r = choose_order(g, np.inf, rules.order_rule)
            ok = r.feasible
            keep.append((w[ok], PoolResult(*(getattr(r, f.name)[ok] for f in fields(PoolResult)))))
    out_rows = np.concatenate([k[0] for k in keep])
    out = PoolResult(*(np.concatenate([getattr(k[1], f.name) for k in keep]) for f in fields(PoolResult)))
    return out_rows, out


def _first_node_at_or_beyond(offsets: np.ndarray, cum: np.ndarray, a: np.ndarray, floor_m: np.ndarray) -> np.ndarray:
    """Flat index of the first node of each path ``P_a`` at arc length ``>= floor_m`` (the path's end index,
    one past its last node, where there is none).  Vectorised binary search inside each path."""
    lo, hi = offsets[a].copy(), offsets[a + 1].copy()
    while True:
        active = lo < hi
        if not active.any():
            return lo
        mid = (lo + hi) // 2
        below = active & (cum[np.minimum(mid, len(cum) - 1)] < floor_m)
        lo = np.where(below, mid + 1, lo)
        hi = np.where(active & ~below, mid, hi)


def _rows(a, b, enroute: bool, r: PoolResult) -> dict:
    return {
        "first": a,
        "second": b,
        "enroute": np.full(len(a), enroute),
        "fofo": r.fofo,
        "saving_m": r.saving,
        "length_m": r.length,
        "detour_first_m": r.detour_a,
        "detour_second_m": r.detour_b,
        "shared_m": r.shared,
        "pickup_m": r.pk,
    }


def _concat(*parts: dict) -> dict:
    return {k: np.concatenate([p[k] for p in parts]) for k in _COLUMNS}


def _waiting_pairs(dist, o, d, solo, ii, jj, rules: PairRules) -> dict:
    """POOL(A=i, B=j, h=o_i) and, with both_pickup_orders, POOL(A=j, B=i, h=o_j)."""
    return _best_orientation(dist, o, d, solo, ii, jj, np.full(len(ii), rules.both_pickup_orders), rules)


def _enroute_pairs(dist, o, d, solo, ii, jj, s, path, rules: PairRules) -> dict:
    """POOL(A=i, B=j, h, δ, pre) with i at arc length s of its path (§4.2, oracle_allow_enroute)."""
    offsets, nodes, cum = path
    # Vectorised binary search inside each path: the first node k with cum[k] >= s.
    lo, hi = offsets[ii].copy(), offsets[ii + 1] - 1
    while True:
        active = lo < hi
        if not active.any():
            break
        mid = (lo + hi) // 2
        right = active & (cum[mid] < s)
        lo = np.where(right, mid + 1, lo)
        hi = np.where(active & ~right, mid, hi)
    delta = cum[lo]
    rows, r = _pool_where_possible(dist, o, d, solo, ii, jj, rules, h=nodes[lo], delta=delta, pre=delta - s)
    return _rows(ii[rows], jj[rows], True, r)
