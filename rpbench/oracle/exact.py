"""The exact offline optimum of a lattice city: the simulator's whole offline decision problem as one MILP.

On a *lattice city* (:mod:`rpbench.scenarios.lattice`: a two-way grid whose every arc takes exactly one
batch interval Δt to drive) every vehicle stands at a node in every round: vehicles start at nodes at
t = 0, drive one arc per round, never stand still (a vacant one cruises or is repositioned), and every
pick-up and drop-off falls on a round.  Time is the round index ``k`` and distance the number of blocks
``S(x, y)``; the decisions of every round, with the future known, form a finite problem, modelled here
as an integer flow of vehicles through a time-expanded network (docs/bound.md, "Exact optima on lattice
cities", proves that its optimum is the largest saving of any run of the simulator, OPT):

* **free states** ``(x, k)``: a vacant vehicle at node ``x`` in round ``k``.  A free arc
  ``(x, k) -> (y, k+1)`` for every network arc ``x -> y`` (cruising and repositioning are walks; a
  vehicle cannot stand).  Vehicle ``v`` enters at ``(x_v, 0)``; all leave at the last round ``T``.
* **approach** ``(x, k) -> P(A, k, k_p)``: in round ``k`` (inside A's patience) the vacant vehicle at
  ``x`` takes order A, ``S(x, o_A) · block <= R̄``, and picks it up in round ``k_p = k + S(x, o_A)``.
* **pair** arcs, the saving ``e = l_A + l_B - L`` of POOL (docs/algorithms.md §1.1): B joins A's vehicle
  in a round ``j`` of B's patience, ``j >= k`` (``j = k``: a two-passenger trip, both waiting) and before
  A is dropped.  Up to the pick-up (``j <= k_p``) the vehicle turns at ``h = o_A`` (A14); these arcs leave
  ``P(A, k, k_p)``.  Later, at ``h`` = the node of A's path reached in round ``j``; these leave
  ``Q(A, k_p)`` (fed by every ``P(A, ·, k_p)``: they do not depend on ``k``).  The pair ends at its last
  drop-off node in round ``k_p + L/block``.  Per (A, B, service order, pick-up round) only the earliest
  feasible turning node is kept: on a bipartite grid ``L`` moves in steps of 2 blocks along A's path,
  so a later turn ends later by an even number of rounds with no more saving, which the vehicle's walk
  can match by driving to a neighbour and back.
* each order is taken at most once (as A or as B); solo service saves nothing and is a walk.

Objective: maximise the total saving in blocks (integral, so a dual bound below the incumbent + 1
proves it optimal).  Solved by HiGHS (``scipy.optimize.milp``) or by OR-Tools CP-SAT; :func:`extract_plan`
decomposes the flow into each vehicle's walk and decisions, which :mod:`rpbench.strategies.exact` hands to
the simulator round by round, so the optimum is realised by a checked run.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from rpbench.exceptions import ParameterError, SolverError
from rpbench.geometry import pair_geometry
from rpbench.oracle.pairs import bound_rules, find_candidates
from rpbench.scenarios.base import Scenario

#: Arc kinds of the flow model.
FREE, EXIT, APPROACH, TO_Q, PAIR = range(5)
ARC_KINDS = ("free", "exit", "approach", "to_q", "pair")
#: The MILP solvers the model can be handed to (both exact).
SOLVERS = ("highs", "cp-sat")
#: A pair must save at least this many blocks to enter the model (a pair saving nothing is a walk).
_MIN_SAVING_BLOCKS = 1


@dataclass(frozen=True)
class LatticeView:
    """A lattice city in rounds and blocks: what the model is built from."""

    block_m: float
    steps: np.ndarray  # (n, n) int64: shortest distances in blocks
    arc_tail: np.ndarray
    arc_head: np.ndarray
    first_round: np.ndarray  # per order: the round it is revealed
    last_round: np.ndarray  # per order: the last round before it is cancelled
    origin: np.ndarray
    destination: np.ndarray
    solo: np.ndarray  # blocks
    vehicle_node: np.ndarray
    max_pickup: int  # R̄ in blocks (floor)
    max_detour_m: float
    dist_m: np.ndarray
    path_offsets: np.ndarray
    path_nodes: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.steps)

    @property
    def n_orders(self) -> int:
        return len(self.origin)

    @property
    def horizon(self) -> int:
        """The last round in which any order can still be assigned."""
        return int(self.last_round.max()) if self.n_orders else 0


def lattice_view(scenario: Scenario) -> LatticeView:
    """The scenario in rounds and blocks; :class:`ParameterError` (one line) unless it is a lattice city: every
    arc ``v·Δt`` long, every arc two-way, the network bipartite, every vehicle on duty throughout."""
    net, p = scenario.network, scenario.params
    block = p.speed_mps * p.dt_s
    length = np.asarray(net.arc_length_m, np.float64)
    if not len(length) or np.abs(length - block).max() > 1e-6 * block:
        lo, hi = (float(length.min()), float(length.max())) if len(length) else (0.0, 0.0)
        raise ParameterError(
            f"the exact optimum needs a lattice city, every arc one batch interval long (v·Δt = {block:g} m); "
            f"scenario {scenario.name!r} has arcs of {lo:g}-{hi:g} m (use --scenario lattice)"
        )
    tail, head = np.asarray(net.arc_tail, np.int64), np.asarray(net.arc_head, np.int64)
    if not np.isin(head * net.n_nodes + tail, tail * net.n_nodes + head).all():
        raise ParameterError(f"the exact optimum needs two-way streets; scenario {scenario.name!r} has one-way arcs")
    count = scenario.fleet.online_count
    if count is not None and bool(np.any(np.asarray(count) != len(scenario.fleet))):
        raise ParameterError("the exact optimum needs every vehicle on duty throughout; this fleet has shifts")
    distances = net.distances()
    dist = np.asarray(distances.dist)
    steps_f = dist / block
    steps = np.rint(steps_f).astype(np.int64)
    if not np.isfinite(dist).all() or np.abs(steps_f - steps).max() > 1e-6:
        raise ParameterError(f"scenario {scenario.name!r}: its distances are not whole blocks of {block:g} m")
    colour = steps[0] % 2
    if (colour[tail] == colour[head]).any():
        raise ParameterError(f"the exact optimum needs a bipartite lattice; scenario {scenario.name!r} is not")
    o = scenario.orders
    origin, destination = o.origin.astype(np.int64), o.destination.astype(np.int64)
    offsets, nodes = distances.paths_batch(origin, destination) if len(o) else (np.zeros(1, np.int64), np.zeros(0))
    first, last = order_rounds(o.request_s, o.patience_s, p.dt_s)
    return LatticeView(
        block_m=block,
        steps=steps,
        arc_tail=tail,
        arc_head=head,
        first_round=first,
        last_round=last,
        origin=origin,
        destination=destination,
        solo=steps[origin, destination],
        vehicle_node=np.asarray(scenario.fleet.initial_node, np.int64),
        max_pickup=int(np.floor(p.max_pickup_m / block + 1e-9)),
        max_detour_m=p.max_detour_m,
        dist_m=dist,
        path_offsets=np.asarray(offsets, np.int64),
        path_nodes=np.asarray(nodes, np.int64),
    )


def order_rounds(request_s: np.ndarray, patience_s: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Per order the first round that reveals it (``k·Δt >= t_req``) and the last one before it is cancelled
    (``k·Δt - t_req <= K + 1e-9``), with the simulator's own float comparisons."""
    request = np.asarray(request_s, np.float64)
    patience = np.asarray(patience_s, np.float64)
    first = np.ceil(request / dt_s).astype(np.int64)
    first = np.where((first - 1) * dt_s >= request, first - 1, first)
    first = np.where(first * dt_s < request, first + 1, first)
    last = np.floor((request + patience + 1e-9) / dt_s).astype(np.int64)
    last = np.where((last + 1) * dt_s - request <= patience + 1e-9, last + 1, last)
    last = np.where(last * dt_s - request > patience + 1e-9, last - 1, last)
    return np.maximum(first, 0), last


@dataclass(frozen=True, eq=False)
class ExactModel:
    """The flow model's arcs (one column each) and states (one balance row each)."""

    view: LatticeView
    n_states: int
    n_free_states: int
    kind: np.ndarray  # arc kind (FREE, EXIT, APPROACH, TO_Q, PAIR)
    tail: np.ndarray  # state id
    head: np.ndarray  # state id, -1: leaves the network
    order_a: np.ndarray  # APPROACH, TO_Q, PAIR: the first passenger (else -1)
    order_b: np.ndarray  # PAIR: the joining passenger (else -1)
    round_k: np.ndarray  # APPROACH: the assignment round; PAIR: the pick-up round k_p
    join_round: np.ndarray  # PAIR: the round B joins (k: a two-passenger trip)
    fofo: np.ndarray  # PAIR: A dropped first
    saving: np.ndarray  # PAIR: blocks saved
    supply: np.ndarray  # per state: vehicles entering there
    build_s: float = 0.0

    @property
    def n_arcs(self) -> int:
        return len(self.kind)

    def size(self) -> dict[str, int]:
        return {
            "states": self.n_states,
            "arcs": self.n_arcs,
            **{
                name: int((self.kind == k).sum()) for k, name in enumerate(("free", "exit", "approach", "to_q", "pair"))
            },
        }


@dataclass
class _Arcs:
    """Columns collected per kind, concatenated once."""

    parts: list[dict[str, np.ndarray]] = field(default_factory=list)

    def add(self, kind: int, tail, head, **cols) -> None:
        tail = np.asarray(tail, np.int64)
        n = len(tail)
        part = {"kind": np.full(n, kind, np.int8), "tail": tail, "head": np.asarray(head, np.int64)}
        for name, default in (("order_a", -1), ("order_b", -1), ("round_k", -1), ("join_round", -1)):
            part[name] = np.asarray(cols.get(name, np.full(n, default)), np.int64)
        part["fofo"] = np.asarray(cols.get("fofo", np.zeros(n, bool)), bool)
        part["saving"] = np.asarray(cols.get("saving", np.zeros(n)), np.int64)
        self.parts.append(part)

    def cat(self) -> dict[str, np.ndarray]:
        return {k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]}


def build_exact_model(view: LatticeView, scenario: Scenario) -> ExactModel:
    """The time-expanded flow model of the lattice city (see the module docstring)."""
    t0 = time.perf_counter()
    n, T = view.n_nodes, view.horizon
    steps = view.steps
    free_id = np.arange((T + 1) * n).reshape(T + 1, n)  # state (x, k) -> k·n + x
    reach = _reachable(view, T)  # (T+1, n) bool: some vehicle can stand at x in round k
    arcs = _Arcs()
    # free arcs: (x, k) -> (y, k+1) along every network arc, between reachable states
    k_all = np.repeat(np.arange(T), len(view.arc_tail))
    x_all = np.tile(view.arc_tail, T)
    y_all = np.tile(view.arc_head, T)
    ok = reach[k_all, x_all] & reach[k_all + 1, y_all]
    arcs.add(FREE, free_id[k_all[ok], x_all[ok]], free_id[k_all[ok] + 1, y_all[ok]])
    last = np.flatnonzero(reach[T])
    arcs.add(EXIT, free_id[T, last], np.full(len(last), -1))
    n_free = (T + 1) * n

    pairs = _directed_pairs(view, scenario)
    firsts = np.unique(pairs[0]) if len(pairs[0]) else np.zeros(0, np.int64)
    # approach arcs, and the P(A, k, k_p) states they reach
    p_keys: dict[tuple[int, int, int], int] = {}
    app_tail, app_a, app_k, app_state = [], [], [], []
    for a in firsts.tolist():
        near = np.flatnonzero(steps[:, view.origin[a]] <= view.max_pickup)
        for k in range(int(view.first_round[a]), int(min(view.last_round[a], T)) + 1):
            xs = near[reach[k, near]]
            for x, kp in zip(xs.tolist(), (k + steps[xs, view.origin[a]]).tolist(), strict=True):
                key = (a, k, kp)
                if key not in p_keys:
                    p_keys[key] = n_free + len(p_keys)
                app_tail.append(free_id[k, x])
                app_a.append(a)
                app_k.append(k)
                app_state.append(p_keys[key])
    arcs.add(APPROACH, app_tail, app_state, order_a=app_a, round_k=app_k)
    q_keys: dict[tuple[int, int], int] = {}
    n_pq = n_free + len(p_keys)
    p_list = list(p_keys.items())
    for (a, _k, kp), _sid in p_list:
        if (a, kp) not in q_keys:
            q_keys[(a, kp)] = n_pq + len(q_keys)
    arcs.add(
        TO_Q,
        [sid for _, sid in p_list],
        [q_keys[(a, kp)] for (a, _k, kp), _ in p_list],
        order_a=[a for (a, _, _), _ in p_list],
    )
    _pair_arcs(view, arcs, pairs, p_list, q_keys, free_id, T)
    cols = arcs.cat()
    n_states = n_pq + len(q_keys)
    supply = np.zeros(n_states, np.int64)
    np.add.at(supply, free_id[0, view.vehicle_node], 1)
    return ExactModel(
        view=view,
        n_states=n_states,
        n_free_states=n_free,
        supply=supply,
        build_s=time.perf_counter() - t0,
        **cols,
    )


def _reachable(view: LatticeView, T: int) -> np.ndarray:
    """(T+1, n): whether some vehicle can stand at node x in round k (a walk of exactly k arcs from its start:
    at most k blocks away, of the same parity on the bipartite grid)."""
    k = np.arange(T + 1)[:, None]
    out = np.zeros((T + 1, view.n_nodes), bool)
    for start in np.unique(view.vehicle_node).tolist():
        s = view.steps[start][None, :]
        out |= (s <= k) & ((k - s) % 2 == 0)
    return out


def _directed_pairs(view: LatticeView, scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) with A picked up first, both orientations of every edge of the upper bound's graph (every pair
    the simulator can form is one, docs/bound.md), zero-length orders never pooled."""
    cand = find_candidates(scenario.network.distances(), scenario.orders, bound_rules(scenario.params))
    a = np.concatenate([cand.low, cand.high]).astype(np.int64)
    b = np.concatenate([cand.high, cand.low]).astype(np.int64)
    keep = (view.solo[a] > 0) & (view.solo[b] > 0)
    return a[keep], b[keep]


def _pair_arcs(view: LatticeView, arcs: _Arcs, pairs, p_list, q_keys, free_id, T: int) -> None:
    """The pair arcs out of the P states (B joins by A's pick-up: h = o_A) and the Q states (later: h on A's
    path), each ending at its last drop-off node in round k_p + L (blocks)."""
    by_first: dict[int, np.ndarray] = {}
    pa, pb = pairs
    order = np.argsort(pa, kind="stable")
    for a, grp in _groups(pa[order], pb[order]):
        by_first[a] = grp
    # (1) from P(A, k, k_p): h = o_A, B joins in a round of [k, k_p]
    rows_a, rows_b, rows_k, rows_kp, rows_state = [], [], [], [], []
    for (a, k, kp), sid in p_list:
        bs = by_first.get(a)
        if bs is None:
            continue
        lo = np.maximum(k, view.first_round[bs])
        hi = np.minimum(kp, view.last_round[bs])
        ok = bs[lo <= hi]
        rows_a.append(np.full(len(ok), a))
        rows_b.append(ok)
        rows_k.append(np.maximum(k, view.first_round[ok]))
        rows_kp.append(np.full(len(ok), kp))
        rows_state.append(np.full(len(ok), sid))
    if rows_a:
        a_, b_, j_, kp_, s_ = (
            np.concatenate(r).astype(np.int64) for r in (rows_a, rows_b, rows_k, rows_kp, rows_state)
        )
        _emit(view, arcs, s_, a_, b_, kp_, j_, view.origin[a_], np.zeros(len(a_), np.int64), free_id, T)
    # (2) from Q(A, k_p): B joins in a round j > k_p, the vehicle at node m = j - k_p of A's path
    q_items = list(q_keys.items())
    if not q_items:
        return
    qa = np.array([a for (a, _), _ in q_items], np.int64)
    qkp = np.array([kp for (_, kp), _ in q_items], np.int64)
    qs = np.array([s for _, s in q_items], np.int64)
    rep_a, rep_b, rep_kp, rep_s = [], [], [], []
    for i, a in enumerate(qa.tolist()):
        bs = by_first.get(a)
        if bs is None:
            continue
        rep_a.append(np.full(len(bs), a))
        rep_b.append(bs)
        rep_kp.append(np.full(len(bs), qkp[i]))
        rep_s.append(np.full(len(bs), qs[i]))
    if not rep_a:
        return
    a_, b_, kp_, s_ = (np.concatenate(r).astype(np.int64) for r in (rep_a, rep_b, rep_kp, rep_s))
    m_lo = np.maximum(kp_ + 1, view.first_round[b_]) - kp_
    m_hi = np.minimum(view.last_round[b_], kp_ + view.solo[a_] - 1) - kp_
    for fofo in (True, False):
        m = m_lo.copy()
        found = np.full(len(a_), -1, np.int64)
        active = np.flatnonzero(m <= m_hi)
        while len(active):
            aa, bb, mm = a_[active], b_[active], m[active]
            h = view.path_nodes[view.path_offsets[aa] + mm]
            ok = _feasible(view, aa, bb, h, mm, fofo)
            found[active[ok]] = mm[ok]
            m[active] += 1
            active = active[~ok & (m[active] <= m_hi[active])]
        hit = np.flatnonzero(found >= 0)
        mm = found[hit]
        h = view.path_nodes[view.path_offsets[a_[hit]] + mm]
        _emit(view, arcs, s_[hit], a_[hit], b_[hit], kp_[hit], kp_[hit] + mm, h, mm, free_id, T, only=fofo)


def _groups(keys: np.ndarray, values: np.ndarray):
    """(key, values of the key) over a key-sorted pair of arrays."""
    if not len(keys):
        return
    cut = np.flatnonzero(np.diff(keys)) + 1
    for ks, vs in zip(np.split(keys, cut), np.split(values, cut), strict=True):
        yield int(ks[0]), vs


def _geometry(view: LatticeView, a, b, h, m):
    """POOL of A = ``a`` and B = ``b`` turning at node ``h`` after ``m`` blocks of A's path (pre = 0)."""
    blk = view.block_m
    return pair_geometry(
        view.dist_m,
        view.origin[a],
        view.destination[a],
        view.solo[a] * blk,
        view.origin[b],
        view.destination[b],
        view.solo[b] * blk,
        h,
        m * blk,
        np.zeros(len(a)),
        view.max_detour_m,
    )


def _feasible(view: LatticeView, a, b, h, m, fofo: bool) -> np.ndarray:
    """B's pick-up within R̄ and both detours within D̄ in the service order ``fofo``."""
    g = _geometry(view, a, b, h, m)
    ok = g.fofo_ok if fofo else g.folo_ok
    return ok & (view.steps[h, view.origin[b]] <= view.max_pickup)


def _emit(view, arcs: _Arcs, tail, a, b, kp, j, h, m, free_id, T: int, only: bool | None = None) -> None:
    """Pair arcs from states ``tail`` for each feasible service order (``only``: that one) with a positive
    saving, to the free state of the last drop-off (or out of the network past round T)."""
    if not len(a):
        return
    g = _geometry(view, a, b, h, m)
    pick_ok = view.steps[h, view.origin[b]] <= view.max_pickup
    blk = view.block_m
    for fofo in (True, False) if only is None else (only,):
        length = g.fofo_length if fofo else g.folo_length
        ok = (g.fofo_ok if fofo else g.folo_ok) & pick_ok
        L = np.rint(length / blk).astype(np.int64)
        saving = view.solo[a] + view.solo[b] - L
        ok &= saving >= _MIN_SAVING_BLOCKS
        end = kp + L
        last = np.where(fofo, view.destination[b], view.destination[a])
        head = np.where(end <= T, free_id[np.minimum(end, T), last], -1)
        arcs.add(
            PAIR,
            tail[ok],
            head[ok],
            order_a=a[ok],
            order_b=b[ok],
            round_k=kp[ok],
            join_round=j[ok],
            fofo=np.full(int(ok.sum()), fofo),
            saving=saving[ok],
        )


# ------------------------------------------------------------------ solving
@dataclass(frozen=True)
class ExactSolution:
    """A solve of the model: flows per arc, the objective and the proven bound (blocks), the solver's word."""

    status: str  # "optimal" (proven) or "time_limit"
    x: np.ndarray
    objective: int
    bound: float
    solver: str
    solve_s: float

    @property
    def proven(self) -> bool:
        return self.status == "optimal"


def _matrices(model: ExactModel) -> tuple[sp.csr_matrix, np.ndarray, sp.csr_matrix]:
    """Balance rows (in - out = -supply per state) and order rows (each order taken at most once)."""
    cols = np.arange(model.n_arcs)
    into = model.head >= 0
    rows = np.concatenate([model.head[into], model.tail])
    data = np.concatenate([np.ones(int(into.sum())), -np.ones(model.n_arcs)])
    balance = sp.csr_matrix((data, (rows, np.concatenate([cols[into], cols]))), shape=(model.n_states, model.n_arcs))
    takes = (model.kind == APPROACH) | (model.kind == PAIR)
    who = np.where(model.kind == APPROACH, model.order_a, model.order_b)
    once = sp.csr_matrix(
        (np.ones(int(takes.sum())), (who[takes], cols[takes])), shape=(model.view.n_orders, model.n_arcs)
    )
    return balance, -model.supply.astype(np.float64), once


def _upper_bounds(model: ExactModel) -> np.ndarray:
    n_veh = float(len(model.view.vehicle_node))
    return np.where((model.kind == FREE) | (model.kind == EXIT), n_veh, 1.0)


def solve_exact_model(
    model: ExactModel, *, solver: str = "highs", time_limit_s: float = 600.0, threads: int = 1
) -> ExactSolution:
    """Maximise the total saving; ``solver`` one of :data:`SOLVERS`."""
    if solver not in SOLVERS:
        raise ParameterError(f"exact solver {solver!r} unknown; expected one of {', '.join(SOLVERS)}")
    if model.n_arcs == 0 or not (model.kind == PAIR).any():
        return ExactSolution("optimal", np.zeros(model.n_arcs), 0, 0.0, solver, 0.0)
    t0 = time.perf_counter()
    if solver == "highs":
        out = _solve_highs(model, time_limit_s, threads)
    else:
        out = _solve_cpsat(model, time_limit_s, threads)
    x, objective, bound, status = out
    return ExactSolution(status, x, objective, bound, solver, time.perf_counter() - t0)


def _solve_highs(model: ExactModel, time_limit_s: float, threads: int) -> tuple[np.ndarray, int, float, str]:
    from scipy.optimize import Bounds, LinearConstraint, milp

    balance, rhs, once = _matrices(model)
    c = -model.saving.astype(np.float64)
    res = milp(
        c,
        constraints=[LinearConstraint(balance, rhs, rhs), LinearConstraint(once, -np.inf, 1.0)],
        integrality=np.ones(model.n_arcs),
        bounds=Bounds(np.zeros(model.n_arcs), _upper_bounds(model)),
        options={"time_limit": float(time_limit_s), "mip_rel_gap": 0.0, "disp": False},
    )
    if res.x is None:
        raise SolverError(
            f"exact: HiGHS found no plan for the day's model within {time_limit_s:g} s ({res.message}); raise "
            "--opt exact.time_limit_s"
        )
    x = np.rint(res.x)
    objective = round(float(model.saving @ x))
    bound = -float(getattr(res, "mip_dual_bound", -objective) or -objective)
    proven = res.status == 0 or bound < objective + 1 - 1e-6
    return x, objective, max(bound, float(objective)), "optimal" if proven else "time_limit"


def _solve_cpsat(model: ExactModel, time_limit_s: float, threads: int) -> tuple[np.ndarray, int, float, str]:
    from ortools.sat.python import cp_model

    balance, rhs, once = _matrices(model)
    ub = _upper_bounds(model).astype(np.int64)
    m = cp_model.CpModel()
    xs = [m.new_int_var(0, int(u), f"x{i}") for i, u in enumerate(ub.tolist())]
    for mat, lo, hi in ((balance.tocsr(), rhs, rhs), (once.tocsr(), None, np.ones(once.shape[0]))):
        for r in range(mat.shape[0]):
            idx = mat.indices[mat.indptr[r] : mat.indptr[r + 1]]
            if not len(idx):
                continue
            coef = mat.data[mat.indptr[r] : mat.indptr[r + 1]].astype(np.int64)
            expr = sum(int(cf) * xs[i] for cf, i in zip(coef.tolist(), idx.tolist(), strict=True))
            if lo is not None:
                m.add(expr == int(lo[r]))
            else:
                m.add(expr <= int(hi[r]))
    pair = np.flatnonzero(model.kind == PAIR)
    m.maximize(sum(int(model.saving[i]) * xs[i] for i in pair.tolist()))
    s = cp_model.CpSolver()
    s.parameters.max_time_in_seconds = float(time_limit_s)
    s.parameters.num_workers = max(1, int(threads))
    code = s.solve(m)
    if code not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        raise SolverError(
            f"exact: CP-SAT found no plan for the day's model within {time_limit_s:g} s ({s.status_name(code)}); "
            "raise --opt exact.time_limit_s"
        )
    x = np.array([s.value(v) for v in xs], np.float64)
    objective = round(float(model.saving @ x))
    return x, objective, float(s.best_objective_bound), "optimal" if code == cp_model.OPTIMAL else "time_limit"


# ------------------------------------------------------------------- the plan
@dataclass
class VehiclePlan:
    """One vehicle's part of the plan: its node in every round it is free, and its jobs."""

    vehicle: int
    walk: dict[int, int] = field(default_factory=dict)  # round -> node (free in that round)
    jobs: list[dict[str, Any]] = field(default_factory=list)


@dataclass
class OptimalPlan:
    """The optimum as decisions per round: assignments (vacant and two-passenger), joins, and every free
    vehicle's next node."""

    objective_blocks: int
    block_m: float
    vehicles: list[VehiclePlan]

    @property
    def objective_m(self) -> float:
        return self.objective_blocks * self.block_m

    def by_round(self) -> dict[int, list[dict[str, Any]]]:
        """Round -> the decisions taken in it (``vacant``, ``trip2``, ``join`` with their orders and vehicle)."""
        out: dict[int, list[dict[str, Any]]] = {}
        for vp in self.vehicles:
            for job in vp.jobs:
                job = {**job, "vehicle": vp.vehicle}
                if job["join_round"] == job["assign_round"]:
                    out.setdefault(job["assign_round"], []).append({"kind": "trip2", **job})
                else:
                    out.setdefault(job["assign_round"], []).append({"kind": "vacant", **job})
                    out.setdefault(job["join_round"], []).append({"kind": "join", **job})
        return out


def extract_plan(model: ExactModel, sol: ExactSolution) -> OptimalPlan:
    """Decompose the integer flow into one walk per vehicle (vehicles in id order, arcs in column order)."""
    view = model.view
    n = view.n_nodes
    flow = np.rint(sol.x).astype(np.int64)
    used = np.flatnonzero(flow > 0)
    out_arcs: dict[int, list[int]] = {}
    for c in used[np.argsort(model.tail[used], kind="stable")].tolist():
        out_arcs.setdefault(int(model.tail[c]), []).extend([c] * int(flow[c]))
    plans = []
    for v, start in enumerate(view.vehicle_node.tolist()):
        vp = VehiclePlan(v)
        state = int(start)  # free state (x, 0)
        job: dict[str, Any] = {}
        while state >= 0:
            if state < model.n_free_states:
                k, x = divmod(state, n)
                vp.walk[k] = x
            pending = out_arcs.get(state)
            if not pending:
                break  # a state at the last round without an exit (cannot happen in a balanced flow)
            c = pending.pop()
            kind = int(model.kind[c])
            if kind == APPROACH:
                k, x = divmod(int(model.tail[c]), n)
                job = {"order_a": int(model.order_a[c]), "assign_round": k, "node": x}
            elif kind == PAIR:
                job |= {
                    "order_b": int(model.order_b[c]),
                    "join_round": int(model.join_round[c]),
                    "pickup_round": int(model.round_k[c]),
                    "fofo": bool(model.fofo[c]),
                    "saving_blocks": int(model.saving[c]),
                }
                vp.jobs.append(job)
                job = {}
            state = int(model.head[c])
        plans.append(vp)
    return OptimalPlan(objective_blocks=sol.objective, block_m=view.block_m, vehicles=plans)
