"""Compiled kernels (numba) of the fleet's routes: random cruises, shortest-path node sequences, plan times.

A round replans a few vehicles (assignments, drop-offs, cruises running out), and each replan walked
its route one node at a time in Python: a cruise's random arcs, the predecessor chain of each
shortest path, the arc of each consecutive node pair.  These kernels do the same walks over flat
arrays and give the same results bit for bit: a cruise consumes the same random numbers and picks
the same arc (:meth:`FleetState._random_walk` documents the rule); times and odometers are summed
arc by arc in plan order, as ``np.cumsum`` sums them.

The network's outgoing arcs are passed as CSR arrays (``offsets``, and per arc its head and
length in ``out_arcs`` order); a node sequence whose consecutive nodes are not joined by an arc,
or a pair of nodes without a path, is reported to the caller (a negative count), which raises.  The
kernels that fill a vehicle's plan window take the fleet's windows as one tuple, ``windows``
(:attr:`~rpbench.sim.lookahead.PlanWindows.arrays`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rpbench.model.kernels import read_only
from rpbench.sim.lookahead import fill_row


@njit(cache=True, nogil=True)
def random_walk(offsets: np.ndarray, heads: np.ndarray, node: int, prev: int, u: np.ndarray) -> np.ndarray:
    """``len(u)`` arcs of a random cruise from ``node`` (reached from ``prev``, -1: none).

    At each node the next is ``candidates[int(u_i · len(candidates))]``, the candidates being the
    heads of its outgoing arcs in CSR order without ``prev`` (no U-turn), or all of them at a dead
    end, when only one arc leaves, or at the start without ``prev``.
    """
    out = np.empty(len(u), np.int32)
    for i in range(len(u)):
        lo = offsets[node]
        deg = offsets[node + 1] - lo
        keep = 0
        if deg > 1 and prev >= 0:
            for j in range(lo, lo + deg):
                if heads[j] != prev:
                    keep += 1
        if keep > 0:
            pick = int(u[i] * keep)
            nxt = -1
            for j in range(lo, lo + deg):
                if heads[j] != prev:
                    if pick == 0:
                        nxt = heads[j]
                        break
                    pick -= 1
        else:
            nxt = heads[lo + int(u[i] * deg)]
        out[i] = nxt
        prev = node
        node = nxt
    return out


@njit(cache=True, nogil=True)
def _path_hops(pred: np.ndarray, a: int, b: int) -> int:
    """The arcs of the shortest path from ``a`` to ``b`` read off the predecessor matrix ``pred`` (``pred[o, v]``:
    the node before ``v`` on the shortest path from ``o``); -1 when there is none."""
    hops = 0
    while b != a:
        b = pred[a, b]
        if b < 0:
            return -1
        hops += 1
    return hops


@njit(cache=True, nogil=True)
def _write_path(pred: np.ndarray, a: int, b: int, out: np.ndarray, end: int) -> None:
    """The shortest path from ``a`` to ``b`` without ``a`` (:func:`_path_hops` nodes), written into ``out`` so that
    ``b`` lands at ``end``: backwards from ``b``, as the predecessor matrix gives it."""
    while b != a:
        out[end] = b
        end -= 1
        b = pred[a, b]


@njit(cache=True, nogil=True)
def route_through(pred: np.ndarray, waypoints: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """The shortest-path nodes visiting ``waypoints`` after the first (the start node left out).

    ``reach[i]`` receives the 1-based position in the result at which waypoint ``i + 1`` is reached.
    Paths are read off the predecessor matrix ``pred`` (``pred[o, v]``: the node before ``v`` on the
    shortest path from ``o``); a missing path gives an empty result and ``reach[0] = -1 - i`` for
    the first segment ``i`` without one.
    """
    n_seg = len(waypoints) - 1
    total = 0
    for s in range(n_seg):
        hops = _path_hops(pred, waypoints[s], waypoints[s + 1])
        if hops < 0:
            reach[0] = -1 - s
            return np.empty(0, np.int32)
        total += hops
        reach[s] = total
    tail = np.empty(total, np.int32)
    for s in range(n_seg):
        _write_path(pred, waypoints[s], waypoints[s + 1], tail, reach[s] - 1)
    return tail


@njit(cache=True, nogil=True)
def plan_arrays(
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    start: int,
    tail: np.ndarray,
    t0: float,
    odo0: float,
    speed: float,
    nodes: np.ndarray,
    tt: np.ndarray,
    odo: np.ndarray,
) -> int:
    """Fill a plan driving ``start`` then ``tail``: its ``nodes``, the time ``tt`` and odometer ``odo`` at each.

    Distances are summed arc by arc from the start (``cum``), ``tt = t0 + cum / speed`` and
    ``odo = odo0 + cum``.  Returns -1, or the position in ``tail`` of the first node not joined to its
    predecessor by an arc.
    """
    nodes[0] = start
    tt[0] = t0 + 0.0 / speed
    odo[0] = odo0 + 0.0
    cum = 0.0
    u = start
    for i in range(len(tail)):
        v = tail[i]
        found = False
        for j in range(offsets[u], offsets[u + 1]):
            if heads[j] == v:
                cum += lengths[j]
                found = True
                break
        if not found:
            return i
        nodes[i + 1] = v
        tt[i + 1] = t0 + cum / speed
        odo[i + 1] = odo0 + cum
        u = v
    return -1


@njit(cache=True, nogil=True)
def plan_and_window(
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    start: int,
    tail: np.ndarray,
    t0: float,
    odo0: float,
    speed: float,
    windows: tuple,
    v: int,
    cruising: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:  # pragma: no cover - compiled
    """A new plan of vehicle ``v`` (:func:`plan_arrays`: its nodes, times and odometers, and -1 or the first
    node of ``tail`` not joined by an arc) and, when it is valid, the vehicle's window over it from its
    first node (:func:`~rpbench.sim.lookahead.fill_row`): a replan's two steps in one compiled call."""
    n = len(tail) + 1
    nodes, tt, odo = np.empty(n, np.int32), np.empty(n), np.empty(n)
    bad = plan_arrays(offsets, heads, lengths, start, tail, t0, odo0, speed, nodes, tt, odo)
    if bad < 0:
        fill_row(windows, v, nodes, tt, odo, cruising, 0)
    return nodes, tt, odo, bad


@njit(cache=True, nogil=True)
def cruise_and_window(
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    start: int,
    prev: int,
    u: np.ndarray,
    t0: float,
    odo0: float,
    speed: float,
    windows: tuple,
    v: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:  # pragma: no cover - compiled
    """A new random cruise of vehicle ``v`` from ``start`` (reached from ``prev``): :func:`random_walk` over
    ``u``, then :func:`plan_and_window` of it as a cruising plan: one compiled call for a cruise's start."""
    tail = random_walk(offsets, heads, start, prev, u)
    return plan_and_window(offsets, heads, lengths, start, tail, t0, odo0, speed, windows, v, True)


@njit(cache=True, nogil=True)
def routed_plans(
    pred: np.ndarray,
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    speed: float,
    waypoints: np.ndarray,
    wp_start: np.ndarray,
    t0: np.ndarray,
    odo0: np.ndarray,
    reach: np.ndarray,
    vehicles: np.ndarray,
    windows: tuple,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int, int]:  # pragma: no cover - compiled
    """Many replans' new plans at once: route ``i`` drives the shortest paths through its waypoints
    ``waypoints[wp_start[i]:wp_start[i + 1]]`` (as :func:`route_through` finds them) from time ``t0[i]`` and
    odometer ``odo0[i]`` (as :func:`plan_arrays` times them), and vehicle ``vehicles[i]``'s window is filled
    over it from its first node (:func:`~rpbench.sim.lookahead.fill_row`).

    Returns the plans' nodes, times and odometers one after another with their offsets, then ``(-1, 0, 0)``,
    or the first route that failed, its segment and why (1: no path, 2: no arc; nothing is filled then).
    ``reach`` receives each route's plan index of each waypoint after its first, routes one after another.
    """
    n_routes = len(wp_start) - 1
    plan_start = np.zeros(n_routes + 1, np.int64)
    for i in range(n_routes):  # the plans' lengths, and each waypoint's place in its plan
        total = 0
        r0 = wp_start[i] - i
        for s in range(wp_start[i + 1] - wp_start[i] - 1):
            hops = _path_hops(pred, waypoints[wp_start[i] + s], waypoints[wp_start[i] + s + 1])
            if hops < 0:
                return np.empty(0, np.int32), np.empty(0), np.empty(0), plan_start, i, s, 1
            total += hops
            reach[r0 + s] = total
        plan_start[i + 1] = plan_start[i] + total + 1
    n = plan_start[n_routes]
    nodes, tt, odo = np.empty(n, np.int32), np.empty(n), np.empty(n)
    for i in range(n_routes):
        p0, p1 = plan_start[i], plan_start[i + 1]
        r0 = wp_start[i] - i
        nodes[p0] = waypoints[wp_start[i]]
        for s in range(wp_start[i + 1] - wp_start[i] - 1):
            _write_path(pred, waypoints[wp_start[i] + s], waypoints[wp_start[i] + s + 1], nodes, p0 + reach[r0 + s])
        bad = plan_arrays(
            offsets, heads, lengths, nodes[p0], nodes[p0 + 1 : p1], t0[i], odo0[i], speed,
            nodes[p0:p1], tt[p0:p1], odo[p0:p1],
        )  # fmt: skip
        if bad >= 0:
            return nodes, tt, odo, plan_start, i, bad, 2
    _fill_windows(windows, vehicles, nodes, tt, odo, plan_start, False)
    return nodes, tt, odo, plan_start, -1, 0, 0


@njit(cache=True, nogil=True)
def repositioned_plans(
    pred: np.ndarray,
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    speed: float,
    starts: np.ndarray,
    targets: np.ndarray,
    u: np.ndarray,
    t0: np.ndarray,
    odo0: np.ndarray,
    vehicles: np.ndarray,
    windows: tuple,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int]:  # pragma: no cover - compiled
    """Many vacant vehicles' new cruising plans at once: plan ``i`` drives the shortest path from
    ``starts[i]`` to ``targets[i]`` (as :func:`route_through` finds it), then a random cruise over the numbers
    ``u[i]`` from the target, having come from the node before it, or from the start when the path has at most
    one arc (:func:`random_walk`); it is timed from ``t0[i]`` and odometer ``odo0[i]`` (:func:`plan_arrays`)
    and vehicle ``vehicles[i]``'s window is filled over it as a cruise's.

    Returns the plans' nodes, times and odometers one after another with their offsets, then ``(-1, 0)``, or
    the first plan that failed and why (1: no path, 2: no arc; nothing is filled then).
    """
    n_plans = len(starts)
    n_walk = u.shape[1]
    plan_start = np.zeros(n_plans + 1, np.int64)
    hops = np.zeros(n_plans, np.int64)
    for i in range(n_plans):  # the paths' lengths
        hops[i] = _path_hops(pred, starts[i], targets[i])
        if hops[i] < 0:
            return np.empty(0, np.int32), np.empty(0), np.empty(0), plan_start, i, 1
        plan_start[i + 1] = plan_start[i] + 1 + hops[i] + n_walk
    n = plan_start[n_plans]
    nodes, tt, odo = np.empty(n, np.int32), np.empty(n), np.empty(n)
    for i in range(n_plans):
        p0, p1 = plan_start[i], plan_start[i + 1]
        a = starts[i]
        nodes[p0] = a
        _write_path(pred, a, targets[i], nodes, p0 + hops[i])
        prev = nodes[p0 + hops[i] - 1] if hops[i] > 1 else a
        nodes[p0 + 1 + hops[i] : p1] = random_walk(offsets, heads, targets[i], prev, u[i])
        bad = plan_arrays(
            offsets, heads, lengths, nodes[p0], nodes[p0 + 1 : p1], t0[i], odo0[i], speed,
            nodes[p0:p1], tt[p0:p1], odo[p0:p1],
        )  # fmt: skip
        if bad >= 0:
            return nodes, tt, odo, plan_start, i, 2
    _fill_windows(windows, vehicles, nodes, tt, odo, plan_start, True)
    return nodes, tt, odo, plan_start, -1, 0


@njit(cache=True, nogil=True)
def _fill_windows(
    windows: tuple,
    vehicles: np.ndarray,
    nodes: np.ndarray,
    tt: np.ndarray,
    odo: np.ndarray,
    plan_start: np.ndarray,
    cruising: bool,
) -> None:  # pragma: no cover - compiled
    """Vehicle ``vehicles[i]``'s window filled over plan ``i`` of plans laid one after another (offsets
    ``plan_start``) from its first node (:func:`~rpbench.sim.lookahead.fill_row`)."""
    for i in range(len(vehicles)):
        p0, p1 = plan_start[i], plan_start[i + 1]
        fill_row(windows, vehicles[i], nodes[p0:p1], tt[p0:p1], odo[p0:p1], cruising, 0)


@njit(cache=True, nogil=True)
def extended_cruise(
    offsets: np.ndarray,
    heads: np.ndarray,
    lengths: np.ndarray,
    nodes: np.ndarray,
    tt: np.ndarray,
    odo: np.ndarray,
    speed: float,
    u: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:  # pragma: no cover - compiled
    """A cruising plan (``nodes``, ``tt``, ``odo``) continued by ``len(u)`` random arcs from its last node
    (:func:`random_walk`, having come from the node before it), timed from its last node as
    :func:`plan_arrays` times a plan; and -1, or the position of the first arc not found."""
    n = len(nodes)
    prev = nodes[n - 2] if n > 1 else -1
    walk = random_walk(offsets, heads, nodes[n - 1], prev, u)
    m = len(walk) + 1
    x_nodes, x_tt, x_odo = np.empty(m, np.int32), np.empty(m), np.empty(m)
    bad = plan_arrays(offsets, heads, lengths, nodes[n - 1], walk, tt[n - 1], odo[n - 1], speed, x_nodes, x_tt, x_odo)
    out_nodes, out_tt, out_odo = np.empty(n + m - 1, np.int32), np.empty(n + m - 1), np.empty(n + m - 1)
    out_nodes[:n], out_tt[:n], out_odo[:n] = nodes, tt, odo
    out_nodes[n:], out_tt[n:], out_odo[n:] = x_nodes[1:], x_tt[1:], x_odo[1:]
    return out_nodes, out_tt, out_odo, bad


@njit(cache=True, nogil=True)
def trajectory_keep(
    nodes: np.ndarray, tt: np.ndarray, starts: np.ndarray, eps: float, t_end: float
) -> np.ndarray:  # pragma: no cover - compiled
    """Which entries of a vehicle's plan chunks (``starts``: their offsets) its trajectory keeps.

    A chunk's first node is dropped when it is the last kept node at a time no earlier (within
    ``eps``); then every node after ``t_end`` (within ``eps``), except the first.
    """
    keep = np.ones(len(nodes), np.bool_)
    kept = False
    last_node, last_tt = 0, 0.0
    for i in range(len(starts) - 1):
        s, e = starts[i], starts[i + 1]
        if e == s:
            continue
        if kept and last_node == nodes[s] and last_tt >= tt[s] - eps:
            keep[s] = False
            s += 1
        if e > s:
            kept = True
            last_node, last_tt = nodes[e - 1], tt[e - 1]
    for j in range(1, len(nodes)):
        if not tt[j] <= t_end + eps:
            keep[j] = False
    return keep


@njit(cache=True, nogil=True)
def fleet_trajectory_keep(
    nodes: np.ndarray, tt: np.ndarray, starts: np.ndarray, firsts: np.ndarray, eps: float, t_end: float
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """:func:`trajectory_keep` for every vehicle at once: the chunks of all vehicles one after another
    (``starts``: the chunks' offsets), vehicle ``v`` owning chunks ``firsts[v]`` to ``firsts[v + 1]``.

    Returns the mask over all entries and, per vehicle, how many entries it keeps.
    """
    keep = np.ones(len(nodes), np.bool_)
    counts = np.zeros(len(firsts) - 1, np.int64)
    for v in range(len(firsts) - 1):
        kept = False
        last_node, last_tt = 0, 0.0
        for i in range(firsts[v], firsts[v + 1]):
            s, e = starts[i], starts[i + 1]
            if e == s:
                continue
            if kept and last_node == nodes[s] and last_tt >= tt[s] - eps:
                keep[s] = False
                s += 1
            if e > s:
                kept = True
                last_node, last_tt = nodes[e - 1], tt[e - 1]
        lo, hi = starts[firsts[v]], starts[firsts[v + 1]]
        for j in range(lo + 1, hi):
            if not tt[j] <= t_end + eps:
                keep[j] = False
        for j in range(lo, hi):
            if keep[j]:
                counts[v] += 1
    return keep, counts


def load_route_kernels() -> None:
    """Load (or compile) every kernel now: the first call of each costs a one-off load of its machine code."""
    offsets, heads = np.array([0, 1, 2], np.int64), np.array([1, 0], np.int64)
    random_walk(offsets, heads, 0, -1, np.zeros(1))
    route_through(np.zeros((2, 2), np.int32), np.zeros(2, np.int64), np.zeros(1, np.int64))
    one = np.zeros(1)
    plan_arrays(offsets, heads, one, 0, np.zeros(0, np.int32), 0.0, 0.0, 1.0, np.zeros(1, np.int32), one, one.copy())
    trajectory_keep(np.zeros(1, np.int32), one, np.array([0, 1], np.int64), 0.0, np.inf)
    fleet_trajectory_keep(np.zeros(1, np.int32), one, np.array([0, 1], np.int64), np.array([0, 1], np.int64), 0.0, 1.0)
    extended_cruise(offsets, heads, one, np.zeros(1, np.int32), one, one.copy(), 1.0, np.zeros(1))
    from rpbench.sim.lookahead import PlanWindows

    w = PlanWindows(1)
    cruise_and_window(offsets, heads, one, 0, -1, np.zeros(1), 0.0, 0.0, 1.0, w.arrays, 0)
    z = np.zeros(1, np.int64)
    pred = read_only(np.zeros((2, 2), np.int32))  # a run's predecessor table is read-only: machine code of its own
    route_through(pred, np.zeros(2, np.int64), np.zeros(1, np.int64))
    routed_plans(
        pred, offsets, heads, one, 1.0, np.zeros(2, np.int64), np.array([0, 2], np.int64),
        np.zeros(1), np.zeros(1), z, z.copy(), w.arrays,
    )  # fmt: skip
    repositioned_plans(
        pred, offsets, heads, one, 1.0, z, z.copy(), np.zeros((1, 1)), np.zeros(1), np.zeros(1), z.copy(), w.arrays
    )  # fmt: skip
    plan_and_window(offsets, heads, one, 0, np.zeros(0, np.int32), 0.0, 0.0, 1.0, w.arrays, 0, False)
