"""``bound-optimal``: the bound's value is at least the maximum-weight matching of its graph, proven here.

The checker enumerates the bound's graph itself (every pair of orders inside the widest time window, each
orientation valued by :mod:`.certificate`'s own rule), so a pair left out of the candidate set counts as
much as a pair left out of the matching.  The maximum is then bounded by a dual certificate of the
matching polytope: degree constraints plus the odd-set (blossom) constraints that a cutting-plane loop
finds (the violated odd components of the fractional edges, or odd cycles of its even ones; when there are
none, the exact separator of :mod:`.separation`), solved with HiGHS (one instance, warm-started as rows are
added).  With exact separation the loop ends only when the LP's solution lies in the matching polytope
(Edmonds), where the LP's optimum is the maximum matching.
The solver only searches: the dual it returns is made feasible and summed by numpy here, and any feasible
dual bounds every matching (weak duality), so the verdict rests on that arithmetic, not on the solver's
claim.  Weights are integral (the model's unit), so a dual below ``U + 1`` proves ``max <= U``.  Should the
loop end above ``U + 1`` anyway (its round limit, or a stall), the dual still fixes every edge whose slack
exceeds the gap (no matching using it can reach ``U + 1``), and an exact matching code decides the edges
left, on its own optimality claim: OGDF's Blossom V when the optional ``blossom`` extra is installed (not
PyMatching, which the bound run may have used), else HiGHS's MIP; the check says so (``mip_edges``, and the
method named).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse.csgraph import connected_components

from rpbench.check.certificate import _orientation_weight, all_paths
from rpbench.check.core import TOL_M, TOL_S
from rpbench.check.folder import Folder
from rpbench.check.separation import VIOLATION_TOL, violated_blossoms

#: Pairs (one orientation each) valued per numpy block: bounds memory to a few hundred MB.
CHECK_BLOCK_PAIRS = 1 << 20
#: A weight this close above a multiple of the unit is float noise: rounded down, never up (the checker's
#: rounded weights then never exceed the run's, whose optimum is the bound).
ROUND_SLACK = 1e-6
#: Cutting-plane rounds before the exact matching code decides.
MAX_ROUNDS = 100
#: The loop has stalled when this many rounds of odd sets in a row lowered the dual bound by less than one
#: unit of weight (the weights are integral): reduced-cost fixing and the exact matching code then decide.
STALL_ROUNDS = 5
FRACTIONAL = 1e-6
#: An edge enters the LP when its reduced cost exceeds this, relative to its weight (the solver's tolerance).
PRICING_TOL = 1e-9


def bound_graph(f: Folder) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a, b, weight) of every edge of the upper bound's graph (docs/bound.md), enumerated from the folder's
    orders alone.  An unordered pair lies inside the widest window of its earlier order i,
    ``t_j - t_i <= K_i + (R̄ + l_i)/v`` (the later order joining; i joining waits at most ``K_i``); an
    orientation is valued only when A's detour at ``h = o_A`` is within D̄, which turning later never
    shortens (the triangle inequality along A's shortest path, docs/bound.md step 3)."""
    p = f.params
    t, k, ids = f.col("request_s"), f.col("patience_s"), f.col("order_id")
    rank = np.lexsort((ids, t))
    ts = t[rank]
    reach = k[rank] + (p.max_pickup_m + TOL_M + f.solo[rank]) / p.speed_mps + TOL_S
    hi = np.searchsorted(ts, ts + reach + 1e-9 * (1.0 + np.abs(ts)), side="right")
    count = np.maximum(hi - np.arange(len(ts)) - 1, 0)
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    paths = all_paths(f)
    cum = np.cumsum(count)
    i0 = 0
    while i0 < len(ts):
        i1 = max(i0 + 1, int(np.searchsorted(cum, (cum[i0 - 1] if i0 else 0) + CHECK_BLOCK_PAIRS, side="right")))
        ii = np.repeat(np.arange(i0, min(i1, len(ts))), count[i0:i1])
        if len(ii):
            starts = np.cumsum(count[i0:i1]) - count[i0:i1]
            jj = ii + 1 + np.arange(len(ii)) - np.repeat(starts, count[i0:i1])
            a, b = rank[ii], rank[jj]
            w = np.full(len(a), -np.inf)
            for x, y in ((a, b), (b, a)):
                m = np.flatnonzero(_may_turn_at_origin(f, x, y))
                w[m] = np.fmax(w[m], _orientation_weight(f, x[m], y[m], paths))
            edge = np.isfinite(w)
            parts.append((a[edge], b[edge], w[edge]))
        i0 = i1
    if not parts:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    return tuple(np.concatenate(c) for c in zip(*parts, strict=True))  # type: ignore[return-value]


def _may_turn_at_origin(f: Folder, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A necessary condition of "x first, y joins": x's ride to its destination via o_y within D̄."""
    dist, o, d = f.distances.dist, f.col("origin"), f.col("destination")
    detour = dist[o[x], o[y]] + dist[o[y], d[x]] - f.solo[x]
    return detour <= f.params.max_detour_m + 1e-6 * (1.0 + np.abs(detour))


def unit_values(weight: np.ndarray, unit_m: float) -> np.ndarray:
    """Weights in model units, rounded up as the bound's model does (docs/bound.md), float noise excepted."""
    return np.ceil(weight / unit_m - ROUND_SLACK)


@dataclass
class MatchingProof:
    """What the checker proved about the maximum-weight matching of a graph (weights in integral units)."""

    best: int  # the weight of a matching the checker found (a lower bound on the maximum)
    upper: float  # a verified upper bound on the maximum (a feasible dual's value, or the exact maximum)
    method: str
    odd_sets: int = 0
    #: Edges whose matching an exact code decided (Blossom V, else HiGHS's MIP: ``method`` says which), on its
    #: own optimality claim (None: the dual certificate alone).
    mip_edges: int | None = None
    rounds: int = 0  # LP solves of the cutting-plane loop
    separated: int = 0  # odd sets found by the exact separator (the others: odd components and cycles)


def prove_maximum(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, target: float) -> MatchingProof:
    """A matching and an upper bound on the maximum weight of any matching of ``(n, a, b, w)`` (``w`` positive
    integers); stops as soon as the upper bound is below ``target + 1`` or a matching above ``target`` is
    found; if the cutting-plane loop ends first (its round limit, a stall, or an LP optimum inside the
    matching polytope above the target), an exact matching code decides the edges reduced-cost fixing left."""
    m = len(w)
    if m == 0:
        return MatchingProof(0, 0.0, "no edges")
    w = np.asarray(w, dtype=np.float64)
    sets = OddSets(n, a, b)
    lp = _CuttingPlaneLP(n, a, b, w)
    best = 0
    beat = np.floor(target + 1e-9) + 1  # a matching worth this much would beat the target
    # Reduced-cost fixing, every round: with a dual feasible on the edges ``live`` of value ``upper``, every
    # matching M of them has w(M) <= upper - (the dual slack of M's edges), so one worth ``beat - 1`` (the
    # target) uses only edges of slack <= upper - beat + 1.  The others leave ``live`` (and the LP, the
    # pricing and the odd sets' rows) for good: the proof goes on over the edges that a matching worth the
    # target or more could use.
    live = np.arange(m)
    slack: np.ndarray | None = None
    upper = float("inf")
    history: list[float] = []
    rounds = separated = 0
    for rounds in range(1, MAX_ROUNDS + 1):
        solved = lp.solve()
        if solved is None:
            break
        x, dual = solved
        best = max(best, _rounded_matching(n, a[live], b[live], w[live], x[live]))
        upper, slack = _dual_value(n, a, b, w, sets, dual, live)
        if best > target or upper < beat - 1e-6:
            if len(live) == m:
                return MatchingProof(best, upper, "dual certificate", len(sets), None, rounds, separated)
            # a matching using a fixed edge is worth less than ``beat``: at most beat - 1 (integral weights)
            method = "dual certificate and reduced-cost fixing"
            return MatchingProof(best, float(max(upper, beat - 1)), method, len(sets), None, rounds, separated)
        drop = slack > upper - (beat - 1) + 1e-6  # kept: the edges of matchings worth the target, too
        if drop.any():
            lp.fix(live[drop])
            live, slack = live[~drop], slack[~drop]
        enter = lp.price(sets, dual, live)
        if not len(enter):  # an optimum of the LP over the live edges: did the last odd sets lower it?
            history.append(upper)
            if len(history) > STALL_ROUNDS and history[-1 - STALL_ROUNDS] - upper < 1.0:
                break
        lp.add_columns(enter)  # before the new sets: their rows are added over every column
        first = len(sets)
        found, exact = _cutting_sets(n, a, b, x)
        separated += exact
        if not sets.add(found, live) and not len(enter):
            break  # x is in the matching polytope of the live edges: the LP's optimum is their maximum
        lp.add_rows(sets, first)
    if slack is None:
        return dataclasses.replace(_decide(n, a, b, w, sets), mip_edges=len(a), rounds=rounds, separated=separated)
    # The exact code need only decide the graph of the edges left (those of slack within the gap).
    near = live[slack <= upper - beat + 1e-6]
    proof = _decide(n, a[near], b[near], w[near], OddSets(n, a[near], b[near]))
    if proof.best < beat:  # no matching of the whole graph reaches ``beat`` either
        return MatchingProof(
            max(best, proof.best),
            float(max(proof.best, beat - 1)),
            f"dual certificate and reduced-cost fixing; {proof.method} on the {len(near)} edges left",
            len(sets),
            len(near),
            rounds,
            separated,
        )
    return MatchingProof(proof.best, float(proof.best), proof.method, len(sets), len(near), rounds, separated)


class _CuttingPlaneLP:
    """The matching LP ``max w·x, degree <= 1, x >= 0`` plus the loop's odd-set rows, in one HiGHS instance
    over a growing subset of the edges (column generation): an edge enters when its reduced cost under the
    last dual is positive, so each solve is a small LP, re-solved by the dual simplex from its last basis,
    and only the pricing, a numpy pass, touches every edge.  An LP over every edge of the full day took
    minutes a round afresh and 20 s warm.  HiGHS only searches: its duals are made feasible over every edge
    and summed by :func:`_dual_value`."""

    def __init__(self, n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray):
        import highspy

        self.n, self.a, self.b, self.w = n, a, b, w
        self.h = h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        h.setOptionValue("threads", 1)
        self.column = np.full(len(w), -1, np.int64)  # each edge's column in the LP (-1: not in it yet)
        self.edges = np.zeros(0, np.int64)  # the LP's columns, as edges
        self.sets: OddSets | None = None
        empty = np.zeros(0, np.int32)
        status = h.passModel(
            0,
            n,
            0,
            int(highspy.MatrixFormat.kColwise),
            int(highspy.ObjSense.kMinimize),
            0.0,
            np.zeros(0),
            np.zeros(0),
            np.zeros(0),
            np.full(n, -highspy.kHighsInf),
            np.ones(n),
            np.zeros(1, np.int32),
            empty,
            np.zeros(0),
            empty,
        )
        self.ok = status.name != "kError"
        self.add_columns(_initial_edges(n, a, b, w))

    def add_columns(self, edges: np.ndarray) -> None:
        """Edges ``edges`` (not yet in the LP) as columns: their degree rows and the rows of the odd sets
        holding them."""
        import highspy

        if not len(edges):
            return
        rows = [self.a[edges], self.b[edges]]
        cols = [np.arange(len(edges)), np.arange(len(edges))]
        if self.sets is not None and len(self.sets):
            local = np.full(len(self.w), -1, np.int64)
            local[edges] = np.arange(len(edges))
            inside = np.flatnonzero(local[self.sets.edge] >= 0)
            rows.append(self.n + self.sets.set_of[inside])
            cols.append(local[self.sets.edge[inside]])
        block = sp.csc_matrix(
            (np.ones(sum(len(r) for r in rows)), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.n + (len(self.sets) if self.sets is not None else 0), len(edges)),
        )
        self.h.addCols(
            len(edges),
            -self.w[edges],
            np.zeros(len(edges)),
            np.full(len(edges), highspy.kHighsInf),
            block.nnz,
            block.indptr[:-1].astype(np.int32),
            block.indices.astype(np.int32),
            block.data,
        )
        self.column[edges] = len(self.edges) + np.arange(len(edges))
        self.edges = np.r_[self.edges, edges]

    def add_rows(self, sets: OddSets, first: int) -> None:
        """The rows of the odd sets from index ``first`` on, over the edges in the LP."""
        import highspy

        self.sets = sets
        entry = np.flatnonzero((sets.set_of >= first) & (self.column[sets.edge] >= 0))
        rows = sp.csr_matrix(
            (np.ones(len(entry)), (sets.set_of[entry] - first, self.column[sets.edge[entry]])),
            shape=(len(sets) - first, len(self.edges)),
        )
        self.h.addRows(
            rows.shape[0],
            np.full(rows.shape[0], -highspy.kHighsInf),
            sets.capacity[first:].astype(np.float64),
            rows.nnz,
            rows.indptr[:-1].astype(np.int32),
            rows.indices.astype(np.int32),
            rows.data.astype(np.float64),
        )

    def solve(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(x of every edge, 0 outside the LP; dual of every row, for ``max w·x``), or None when HiGHS reached
        no optimum."""
        if not self.ok:
            return None
        self.h.run()
        if self.h.getModelStatus().name != "kOptimal":
            return None
        sol = self.h.getSolution()
        x = np.zeros(len(self.w))
        x[self.edges] = np.asarray(sol.col_value, np.float64)
        return x, -np.asarray(sol.row_dual, np.float64)

    def price(self, sets: OddSets, dual: np.ndarray, live: np.ndarray) -> np.ndarray:
        """The edges to add: live, outside the LP, of positive reduced cost under ``dual`` (each vertex's
        largest).  None left: ``dual`` is an optimal dual of the LP over the live edges."""
        reduced = self.w[live] - _cover(self.n, self.a, self.b, sets, dual, live)
        out = (reduced > PRICING_TOL * (1.0 + self.w[live])) & (self.column[live] < 0)
        return _most_violated(self.a, self.b, live[out], reduced[out])

    def fix(self, edges: np.ndarray) -> None:
        """Edges that no matching beating the target uses: those in the LP are held at 0."""
        cols = self.column[edges]
        cols = cols[cols >= 0].astype(np.int32)
        if len(cols):
            zero = np.zeros(len(cols))
            self.h.changeColsBounds(len(cols), cols, zero, zero)


def _initial_edges(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The LP's first columns: each vertex's heaviest edge (most of them are in the optimum's support; the
    pricing adds the rest)."""
    if not len(w):
        return np.zeros(0, np.int64)
    ends = np.r_[a, b]
    edge = np.r_[np.arange(len(w)), np.arange(len(w))]
    order = np.lexsort((-w[edge], ends))
    first = np.r_[True, ends[order][1:] != ends[order][:-1]]
    return np.unique(edge[order][first])


def _most_violated(a: np.ndarray, b: np.ndarray, edge: np.ndarray, reduced: np.ndarray) -> np.ndarray:
    """Among the edges ``edge`` of reduced costs ``reduced``, each vertex's edge of the largest (partial
    pricing: the LP stays near the size of the optimum's support instead of taking every violated edge of a
    poor first dual)."""
    if not len(edge):
        return edge
    ends, both, value = np.r_[a[edge], b[edge]], np.r_[edge, edge], np.r_[reduced, reduced]
    order = np.lexsort((-value, ends))
    first = np.r_[True, ends[order][1:] != ends[order][:-1]]
    return np.unique(both[order][first])


def _cover(n: int, a: np.ndarray, b: np.ndarray, sets: OddSets, dual: np.ndarray, live: np.ndarray) -> np.ndarray:
    """Each live edge's cover ``y_a + y_b + Σ z`` (the odd sets holding it) under ``dual`` clipped at 0."""
    y, z = np.maximum(dual[:n], 0.0), np.maximum(dual[n:], 0.0)
    inside = np.bincount(sets.edge, weights=z[sets.set_of], minlength=len(a))[live]
    return y[a[live]] + y[b[live]] + inside


def _degree(n: int, a: np.ndarray, b: np.ndarray) -> sp.csr_matrix:
    edges = np.arange(len(a))
    return sp.csr_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[edges, edges])), shape=(n, len(a)))


class OddSets:
    """The odd vertex sets found so far, each with the edges inside it (computed once, when it is added: the
    loop's rows and dual read them every round, and the full day's graph has millions of edges)."""

    def __init__(self, n: int, a: np.ndarray, b: np.ndarray):
        self.n, self.a, self.b = n, a, b
        self.capacity = np.zeros(0)  # (|S| - 1) / 2 per set
        self.set_of = np.zeros(0, np.int64)  # per (set, inside edge) entry: the set
        self.edge = np.zeros(0, np.int64)  # and the edge

    def __len__(self) -> int:
        return len(self.capacity)

    def add(self, sets: list[np.ndarray], live: np.ndarray | None = None) -> bool:
        """Add ``sets`` (vertex sets, disjoint or not), with their inside edges among ``live`` (None: every edge);
        False when there are none."""
        if not sets:
            return False
        edges = np.arange(len(self.a)) if live is None else live
        ea, eb = self.a[edges], self.b[edges]
        for layer in _disjoint_layers(sets):  # one pass over the edges per layer of disjoint sets
            label = np.full(self.n, -1, np.int64)
            for i in layer:
                label[sets[i]] = len(self) + i
            la, lb = label[ea], label[eb]
            inside = (la >= 0) & (la == lb)
            self.set_of = np.r_[self.set_of, la[inside]]
            self.edge = np.r_[self.edge, edges[inside]]
        self.capacity = np.r_[self.capacity, [(len(s) - 1) // 2 for s in sets]]
        return True

    def rows(self) -> sp.csr_matrix:
        """One row per set: 1 on every edge inside it."""
        shape = (len(self), len(self.a))
        return sp.csr_matrix((np.ones(len(self.edge)), (self.set_of, self.edge)), shape=shape)


def _disjoint_layers(sets: list[np.ndarray]) -> list[list[int]]:
    """The indices of ``sets`` in groups of pairwise disjoint sets (each set in the first group it fits: the
    exact separator's sets are laminar, a few deep)."""
    layers: list[tuple[list[int], set[int]]] = []
    for i, s in enumerate(sets):
        members = set(s.tolist())
        for indices, used in layers:
            if used.isdisjoint(members):
                indices.append(i)
                used |= members
                break
        else:
            layers.append(([i], members))
    return [indices for indices, _ in layers]


def _dual_value(
    n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, sets: OddSets, dual: np.ndarray, live: np.ndarray
) -> tuple[float, np.ndarray]:
    """The value of the solver's dual made feasible on the edges ``live`` here, and each live edge's slack
    under it (cover - w >= 0): y, z clipped at 0, each edge's shortfall (float tolerance of the solver, or an
    edge not yet priced into the LP) added to its first end.  Feasible, so an upper bound on every matching
    of the live edges."""
    y, z = np.maximum(dual[:n], 0.0), np.maximum(dual[n:], 0.0)
    al, bl, wl = a[live], b[live], w[live]
    inside = np.bincount(sets.edge, weights=z[sets.set_of], minlength=len(a))[live]
    short = np.maximum(wl - (y[al] + y[bl] + inside), 0.0)
    np.maximum.at(y, al, y[al] + short)
    slack = np.maximum(y[al] + y[bl] + inside - wl, 0.0)
    return float(y.sum() + z @ sets.capacity), slack


def _rounded_matching(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, x: np.ndarray) -> int:
    """The weight of the edges with x > 1/2 (a matching: two such edges at one node would exceed degree 1)."""
    take = x > 0.5
    if (np.bincount(np.r_[a[take], b[take]], minlength=n) > 1).any():
        return 0
    return int(w[take].sum())


def _cutting_sets(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray) -> tuple[list[np.ndarray], int]:
    """Odd sets whose blossom inequalities the LP solution ``x`` violates, and how many of them only the exact
    separator found: the odd components and cycles of its fractional edges that are violated (cheap, and most
    sets of the early rounds) and the exact separator's (:mod:`.separation`: a most violated set, which a
    large, barely violated odd component can hide), each set once.  None only when ``x`` lies in the
    matching polytope."""
    support = np.flatnonzero(x > FRACTIONAL)
    sa, sb, sx = a[support], b[support], x[support]
    frac = sx < 1 - FRACTIONAL
    found = _violated_disjoint(n, sa, sb, sx, _odd_components(n, sa[frac], sb[frac]))
    seen = {tuple(np.sort(s).tolist()) for s in found}
    exact = [s for s in violated_blossoms(n, sa, sb, sx) if tuple(np.sort(s).tolist()) not in seen]
    return found + exact, len(exact)


def _violated_disjoint(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray, sets: list[np.ndarray]) -> list[np.ndarray]:
    """The sets among the disjoint ``sets`` that are odd, of 3 or more vertices, and whose blossom inequality
    ``x`` violates (by more than :data:`.separation.VIOLATION_TOL`), in one pass over the edges."""
    if not sets:
        return []
    label = np.full(n, -1, np.int64)
    for i, members in enumerate(sets):
        label[members] = i
    la, lb = label[a], label[b]
    inside = (la >= 0) & (la == lb)
    weight = np.bincount(la[inside], weights=x[inside], minlength=len(sets))
    size = np.array([len(members) for members in sets])
    keep = (size >= 3) & (size % 2 == 1) & (weight > (size - 1) / 2 + VIOLATION_TOL)
    return [sets[i] for i in np.flatnonzero(keep)]


def _odd_components(n: int, a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Disjoint vertex sets of violated blossom constraints among the fractional edges ``(a, b)``: each odd
    component (>= 3 nodes), and in each even component that is not bipartite, the vertices of one odd cycle
    (its edges at 1/2 sum to more than (|S| - 1)/2).  The fractional edges are few (tens to hundreds)."""
    if not len(a):
        return []
    _, label = connected_components(sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
    size = np.bincount(label, minlength=label.max() + 1)
    out = []
    for comp in np.unique(label[a]).tolist():
        members = np.flatnonzero(label == comp) if size[comp] % 2 == 1 else None
        if members is not None and len(members) >= 3:
            out.append(members)
        elif members is None:
            inside = label[a] == comp
            cycle = _odd_cycle(a[inside], b[inside])
            if cycle is not None:
                out.append(cycle)
    return out


def _odd_cycle(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The vertices of an odd cycle of the connected graph ``(a, b)`` (None: it is bipartite), by breadth-first
    search: an edge joining two vertices of the same depth closes one with their paths to the root."""
    adjacent: dict[int, list[int]] = {}
    for u, v in zip(a.tolist(), b.tolist(), strict=True):
        adjacent.setdefault(u, []).append(v)
        adjacent.setdefault(v, []).append(u)
    root = int(a[0])
    parent, depth, queue = {root: root}, {root: 0}, [root]
    for u in queue:
        for v in adjacent[u]:
            if v not in depth:
                parent[v], depth[v] = u, depth[u] + 1
                queue.append(v)
            elif depth[v] == depth[u]:
                x, y, cycle = u, v, {u, v}
                while x != y:
                    x, y = parent[x], parent[y]
                    cycle |= {x, y}
                return np.array(sorted(cycle), np.int64)
    return None


def _decide(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, sets: OddSets) -> MatchingProof:
    """The maximum of the graph ``(n, a, b, w)`` by an exact code, on its own optimality claim: OGDF's Blossom V
    (combinatorial, polynomial; not the code the bound run solves with) when the optional ``blossom`` extra is
    installed, else HiGHS's MIP."""
    from rpbench.backends.blossom import blossom_v_matching
    from rpbench.exceptions import SolverNotInstalledError

    try:
        chosen = blossom_v_matching(n, a, b, np.rint(w).astype(np.int64))
    except SolverNotInstalledError:
        return _exact(n, a, b, w, sets)
    x = np.zeros(len(w))
    x[chosen] = 1.0
    value = _rounded_matching(n, a, b, w, x)  # 0 if Blossom V's edges were not a matching
    return MatchingProof(value, float(value), "Blossom V (OGDF; its optimality claim)", len(sets))


def _exact(n: int, a: np.ndarray, b: np.ndarray, w: np.ndarray, sets: OddSets) -> MatchingProof:
    """The HiGHS MIP over the degree and odd-set constraints, no gap allowed (its optimality is the solver's
    claim: the last resort when the certificate did not close)."""
    res = milp(
        -w,
        constraints=LinearConstraint(
            sp.vstack([_degree(n, a, b), sets.rows()]).tocsr(), -np.inf, np.r_[np.ones(n), sets.capacity]
        ),
        integrality=np.ones(len(w)),
        bounds=Bounds(0, 1),
        options={"mip_rel_gap": 0.0},
    )
    if res.status != 0 or res.x is None:
        return MatchingProof(0, float("inf"), "HiGHS MIP (no solution)", len(sets))
    value = _rounded_matching(n, a, b, w, res.x)
    return MatchingProof(value, float(value), "HiGHS MIP (the solver's optimality claim)", len(sets))
