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

    def fill(self, v: int, nodes: np.ndarray, tt: np.ndarray, odo: np.ndarray, cruising: bool, k: int) -> None:
        """Window of vehicle ``v`` over its plan (``nodes``, ``tt``, ``odo``) from plan index ``k``."""
        end = min(len(tt), k + WIDTH)
        m = end - k
        self.tt[v, :m] = tt[k:end]
        self.tt[v, m:] = np.inf
        self.node[v, :m] = nodes[k:end]
        self.odo[v, :m] = odo[k:end]
        self.base[v] = k
        self.length[v] = m
        self.tt_before[v] = tt[k - 1] if k > 0 else -np.inf
        self.last[v] = len(tt) - 1
        self.cruising[v] = cruising

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
