"""The next few plan nodes of every vehicle in flat arrays, for vectorised position lookups.

A moving vehicle passes a plan node almost every round, so looking its
position up in its own plan (a Python step per vehicle) dominated round
building.  :class:`PlanWindows` copies a window of ``WIDTH`` plan nodes ahead
of each vehicle into ``(vehicles, WIDTH)`` arrays; one numpy pass then finds
the next node of every vehicle whose answer lies inside its window, and only
vehicles that ran past their window (about once every ``WIDTH`` nodes) go back
to their plan.  A window is dropped whenever its vehicle's plan changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

#: Plan nodes per window: a vehicle crosses about one node per 10 s round.
WIDTH = 16


@dataclass(frozen=True)
class Found:
    """Next plan nodes of the vehicles whose window answered (``vehicles``; the others in ``missed``)."""

    vehicles: np.ndarray
    k: np.ndarray  # plan index of the next node
    node: np.ndarray
    tt: np.ndarray  # time at that node
    odo: np.ndarray  # odometer at that node
    at_end: np.ndarray  # the node is the plan's last and the plan is not a cruise
    missed: np.ndarray


class PlanWindows:
    """Windows of plan nodes ahead of each vehicle (``length`` 0: none)."""

    def __init__(self, n_vehicles: int):
        self.tt = np.full((n_vehicles, WIDTH), np.inf)  # padded with +inf past the window
        self.node = np.zeros((n_vehicles, WIDTH), dtype=np.int64)
        self.odo = np.zeros((n_vehicles, WIDTH))
        self.base = np.zeros(n_vehicles, dtype=np.int64)  # plan index of the window's first node
        self.length = np.zeros(n_vehicles, dtype=np.int64)
        self.tt_before = np.full(n_vehicles, -np.inf)  # time at the node before the window
        self.last = np.zeros(n_vehicles, dtype=np.int64)  # the plan's last index
        self.cruising = np.zeros(n_vehicles, dtype=bool)
        #: The eight arrays in one tuple, as the compiled kernels take them (``windows``; the arrays are
        #: written in place, never replaced).
        self.arrays = (
            self.tt, self.node, self.odo, self.base, self.length, self.tt_before, self.last, self.cruising
        )  # fmt: skip

    def fill(self, v: int, nodes: np.ndarray, tt: np.ndarray, odo: np.ndarray, cruising: bool, k: int) -> None:
        """Window of vehicle ``v`` over its plan (``nodes``, ``tt``, ``odo``) from plan index ``k``."""
        fill_row(self.arrays, v, nodes, tt, odo, cruising, k)

    def drop(self, v: int) -> None:
        self.length[v] = 0

    def find(self, vehicles: np.ndarray, before: float) -> Found:
        """For each vehicle, the first plan node reached at or after time ``before`` (plan ``tt >= before``).

        That is ``searchsorted(tt, before, side="left")`` on the plan: the number of plan times below
        ``before``, since plan times never decrease.  A window answers when its vehicle reached the
        node before it earlier than ``before`` and some window node is not earlier than ``before``.
        """
        window = self.tt[vehicles]
        j = (window < before).sum(axis=1)
        ok = (j < self.length[vehicles]) & (self.tt_before[vehicles] < before)
        hit, j, window = vehicles[ok], j[ok], window[ok]
        k = self.base[hit] + j
        tt = window[np.arange(len(hit)), j]
        return Found(
            vehicles=hit,
            k=k,
            node=self.node[hit, j],
            tt=tt,
            odo=self.odo[hit, j],
            at_end=(k == self.last[hit]) & ~self.cruising[hit],
            missed=vehicles[~ok],
        )


@njit(cache=True, nogil=True)
def fill_row(
    windows: tuple,
    v: int,
    nodes: np.ndarray,
    tt: np.ndarray,
    odo: np.ndarray,
    cruising: bool,
    k: int,
) -> None:  # pragma: no cover - compiled
    """:meth:`PlanWindows.fill` in one compiled call (a round fills a window for every vehicle it replans);
    ``windows``: :attr:`PlanWindows.arrays`."""
    w_tt, w_node, w_odo, base, length, tt_before, last, w_cruising = windows
    m = min(len(tt), k + WIDTH) - k
    for j in range(WIDTH):
        if j < m:
            w_tt[v, j] = tt[k + j]
            w_node[v, j] = nodes[k + j]
            w_odo[v, j] = odo[k + j]
        else:
            w_tt[v, j] = np.inf
    base[v] = k
    length[v] = m
    tt_before[v] = tt[k - 1] if k > 0 else -np.inf
    last[v] = len(tt) - 1
    w_cruising[v] = cruising


@njit(cache=True, nogil=True)
def advance(
    vehicles: np.ndarray,
    before: float,
    t: float,
    windows: tuple,
    next_k: np.ndarray,
    next_node: np.ndarray,
    next_tt: np.ndarray,
    next_odo: np.ndarray,
    idle: np.ndarray,
    missed: np.ndarray,
) -> int:
    """Move each stale vehicle's cached next node (``next_*``, ``idle``) on to its first plan node at or after
    ``before``, as :meth:`PlanWindows.find` finds it; a vehicle is stale when it is not idle and its cached node
    lies before ``before``.  Stale vehicles whose window cannot answer are written to ``missed`` in the order
    given; returns their number.  One compiled pass instead of a numpy pass per field: a round asks this for
    every vacant and every partly occupied vehicle (``windows``: :attr:`PlanWindows.arrays`).
    """
    w_tt, w_node, w_odo, base, length, tt_before, last, cruising = windows
    n_missed = 0
    for i in range(len(vehicles)):
        v = vehicles[i]
        if not next_tt[v] < before or idle[v]:
            continue
        m = length[v]
        j = 0
        while j < m and w_tt[v, j] < before:
            j += 1
        if j >= m or not tt_before[v] < before:
            missed[n_missed] = v
            n_missed += 1
            continue
        k = base[v] + j
        tt = w_tt[v, j]
        next_k[v] = k
        next_node[v] = w_node[v, j]
        idle[v] = k == last[v] and not cruising[v] and tt <= t
        next_tt[v] = tt
        next_odo[v] = w_odo[v, j]
    return n_missed


@njit(cache=True, nogil=True)
def refill_from_plan(
    v: int,
    k: int,
    before: float,
    t: float,
    nodes: np.ndarray,
    tt: np.ndarray,
    odo: np.ndarray,
    cruising: bool,
    next_k: np.ndarray,
    next_node: np.ndarray,
    next_tt: np.ndarray,
    next_odo: np.ndarray,
    idle: np.ndarray,
    windows: tuple,
) -> int:  # pragma: no cover - compiled
    """Vehicle ``v``'s cached next node and window from its plan (``nodes``, ``tt``, ``odo``) when its window
    could not answer: at plan index ``k``, or (``k < 0``) at its first node reached at or after ``before``
    (``searchsorted(tt, before)``).  Returns that index, or -1, changing nothing, when it lies past the plan's
    end (the caller extends a cruise or stands the vehicle at its last node, then passes the index);
    ``windows``: :attr:`PlanWindows.arrays`."""
    if k < 0:
        k = int(np.searchsorted(tt, before))
        if k >= len(nodes):
            return -1
    tt_k = tt[k]
    next_k[v] = k
    next_node[v] = nodes[k]
    idle[v] = k == len(nodes) - 1 and tt_k <= t and not cruising
    next_tt[v] = tt_k
    next_odo[v] = odo[k]
    fill_row(windows, v, nodes, tt, odo, cruising, k)
    return k


@njit(cache=True, nogil=True)
def gather_positions(
    vehicles: np.ndarray,
    t: float,
    speed: float,
    next_k: np.ndarray,
    next_node: np.ndarray,
    next_tt: np.ndarray,
    idle: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per vehicle: the plan index of its cached next node, the node, and the metres before it at time ``t``."""
    n = len(vehicles)
    k, node, pre = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    for i in range(n):
        v = vehicles[i]
        k[i] = next_k[v]
        node[i] = next_node[v]
        pre[i] = 0.0 if idle[v] else max(0.0, (next_tt[v] - t) * speed)
    return k, node, pre


def load_lookahead_kernels() -> None:
    """Load (or compile) the kernels now: the first call of each costs a one-off load of its machine code."""
    w = PlanWindows(1)
    one = np.zeros(1, np.int64)
    advance(
        one,
        0.0,
        0.0,
        w.arrays,
        one.copy(),
        one.copy(),
        np.zeros(1),
        np.zeros(1),
        np.zeros(1, bool),
        one.copy(),
    )
    gather_positions(one, 0.0, 1.0, one, one, np.zeros(1), np.zeros(1, bool))
    refill_from_plan(
        0, -1, 0.0, 0.0, np.zeros(1, np.int32), np.zeros(1), np.zeros(1), False,
        one.copy(), one.copy(), np.zeros(1), np.zeros(1), np.zeros(1, bool), w.arrays,
    )  # fmt: skip
    w.fill(0, np.zeros(1, np.int32), np.zeros(1), np.zeros(1), False, 0)
