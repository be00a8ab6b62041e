"""Foresight: the saving a pair would realise in the simulator, read off the realised orders.

One concept, shared by the clairvoyant strategies (``hindsight``, ``fl-perfect``): given when the first
passenger A is picked up (A's vehicle then drives A's shortest path P_A at the set speed) and the rounds
in which the second, B, may join, :meth:`Foresight.forecast` gives the saving ``l_A + l_B - L`` (Eq. 5)
the simulator would realise.  The vehicle turns at the first node ``h`` of P_A it can have next, in the
window, with ``pre + l(h, o_B) <= R̄`` (before A's pick-up ``h = o_A`` and ``pre = 0``, A14): turning
earlier never lengthens the route (docs/bound.md, step 3), and by the same triangle inequality a node
found this way is the vehicle's next node at the instant found.  Join times are taken as continuous
in the window, so a node whose feasible stretch of road the vehicle crosses between two rounds counts
too; when B can join in the window's first round the forecast is the simulator's saving exactly.

:class:`PickupTimes` says when the passenger of a partly occupied vehicle (V1) is, or was, picked up:
what the simulator's V1 vehicles do, observed from the rounds that assigned them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rpbench.geometry import TOLERANCE_M, choose_order, pair_geometry
from rpbench.scenarios.base import Scenario
from rpbench.strategies.base import RoundState

#: Arc-length offset separating the orders' paths in one sorted array (longer than any path).
_PATH_GAP_M = 1e8


class Foresight:
    """The realised orders of a scenario, their round windows and shortest paths, and pair forecasts."""

    def __init__(self, scenario: Scenario):
        o = scenario.orders
        p = scenario.params
        distances = scenario.network.distances()
        self.params = p
        self.dist = np.asarray(distances.dist)
        self.origin = o.origin.astype(np.intp)
        self.destination = o.destination.astype(np.intp)
        self.request = np.asarray(o.request_s, np.float64)
        self.patience = np.asarray(o.patience_s, np.float64)
        n = len(o)
        self.n = n
        self.solo = self.dist[self.origin, self.destination] if n else np.zeros(0)
        dt = p.dt_s
        # first and last round in which each order can be decided (revealed at k·Δt >= t_req; cancelled
        # once t - t_req > K, the simulator's rule)
        self.first_round = np.ceil(self.request / dt - 1e-9) * dt
        self.last_round = np.floor((self.request + self.patience + 1e-9) / dt) * dt
        # every order's shortest path (the one its vehicle drives) and the arc length at each node
        if n:
            offsets, nodes = distances.paths_batch(self.origin, self.destination)
        else:
            offsets, nodes = np.zeros(1, np.int64), np.zeros(0, np.intp)
        self.path_offsets = np.asarray(offsets, np.int64)
        self.path_nodes = np.asarray(nodes, np.intp)
        lengths = np.diff(self.path_offsets)
        owner = np.repeat(np.arange(n), lengths)
        self.path_cum = self.dist[self.origin[owner], self.path_nodes] if n else np.zeros(0)
        self.path_key = self.path_cum + owner * _PATH_GAP_M  # increasing over all paths

    def join_from(self, b: np.ndarray, after_assign: np.ndarray | float, t: float) -> np.ndarray:
        """The earliest round B can join: revealed, not before ``after_assign`` (A's assignment + Δt), not past."""
        return np.maximum(np.maximum(self.first_round[b], after_assign), t)

    def forecast(
        self,
        a: np.ndarray,
        b: np.ndarray,
        t_lo: np.ndarray,
        t_hi: np.ndarray,
        t_pick: np.ndarray,
        t_pick_early: np.ndarray | None = None,
    ) -> np.ndarray:
        """The saving of B joining A's vehicle in a round of ``[t_lo, t_hi]`` (NaN: cannot), A picked up at
        ``t_pick`` (with ``t_pick_early``: at any time in ``[t_pick_early, t_pick]``) and then driving P_A
        at the set speed.

        The vehicle turns at the first node ``h`` of P_A it can have next with ``pre + l(h, o_B) <= R̄``
        in the window (before the pick-up ``h = o_A``, ``pre = 0``, A14); its saving is POOL's at ``h``
        with ``δ = l(o_A, h)`` (§1.1), in its best feasible service order.  Vectorised: one numpy step per
        path node walked.
        """
        p = self.params
        out = np.full(len(a), np.nan)
        a = np.asarray(a, np.int64)
        b = np.asarray(b, np.int64)
        r_bar = p.max_pickup_m + TOLERANCE_M
        o, dd, solo, dist = self.origin, self.destination, self.solo, self.dist
        # the window exists, and A's detour can be met at all (it only grows along P_A)
        rows = np.flatnonzero(
            (t_lo <= t_hi + 1e-9)
            & (dist[o[a], o[b]] + dist[o[b], dd[a]] - solo[a] <= p.max_detour_m + 1e-6)
            & (solo[a] > TOLERANCE_M)
            & (solo[b] > TOLERANCE_M)
        )
        if not len(rows):
            return out
        aa, bb = a[rows], b[rows]
        v = p.speed_mps
        early = t_pick if t_pick_early is None else t_pick_early
        s_lo = v * np.maximum(0.0, t_lo[rows] - t_pick[rows])
        s_hi = v * np.maximum(0.0, t_hi[rows] - early[rows])
        start = np.searchsorted(self.path_key, s_lo - 1e-6 + aa * _PATH_GAP_M, side="left")
        end = self.path_offsets[aa + 1]
        cum, nodes = self.path_cum, self.path_nodes
        hit = _first_turn(start, end, o[bb], s_lo, s_hi, r_bar, cum, nodes, dist)
        ok = hit >= 0
        if not ok.any():
            return out
        rows, aa, bb, h = rows[ok], aa[ok], bb[ok], hit[ok]
        g = pair_geometry(
            dist,
            o[aa],
            dd[aa],
            solo[aa],
            o[bb],
            dd[bb],
            solo[bb],
            nodes[h],
            cum[h],
            np.zeros(len(h)),
            p.max_detour_m,
        )
        r = choose_order(g, np.inf)
        out[rows[r.feasible]] = r.saving[r.feasible]
        return out


@njit(cache=True, nogil=True)
def _first_turn(
    start: np.ndarray,
    end: np.ndarray,
    origin_b: np.ndarray,
    s_lo: np.ndarray,
    s_hi: np.ndarray,
    r_bar: float,
    cum: np.ndarray,
    nodes: np.ndarray,
    dist: np.ndarray,
) -> np.ndarray:  # pragma: no cover (compiled; covered through Foresight.forecast)
    """For each row, the first path index ``k`` in ``[start, end)`` the vehicle can have next, in the arc
    lengths ``[s_lo, s_hi]`` it can have driven, with ``pre + l(h, o_B) <= R̄`` (-1: none).  The walk stops
    once the node lies more than R̄ beyond ``s_hi``: no later node can be had in time."""
    out = np.full(len(start), -1, np.int64)
    for i in range(len(start)):
        for k in range(start[i], end[i]):
            gap = r_bar - dist[nodes[k], origin_b[i]]  # how far before h the vehicle may still be
            earliest = max(s_lo[i], cum[k] - gap)
            if gap >= 0 and earliest <= min(s_hi[i], cum[k]) + 1e-6:
                out[i] = k
                break
            if cum[k] - r_bar > s_hi[i]:
                break
    return out


class PickupTimes:
    """When the passenger A of each partly occupied vehicle (V1) is picked up.

    On board: from the vehicle's position.  On the way: A was assigned a vacant vehicle in the last round
    the strategy built (assignments are final and only rounds assign), at the pick-up distance of that
    round's vacant option, which the vehicle drives at the set speed.  ``default_s``: the pick-up time
    assumed until one is observed.
    """

    def __init__(self, n: int, speed_mps: float, default_s: float):
        self.speed_mps = speed_mps
        self.default_s = default_s
        self.pick_s = np.full(n, np.nan)
        self._offered: tuple[float, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._observed: list[float] = []

    def offered(self, t: float, orders: np.ndarray, vehicles: np.ndarray, pickup_m: np.ndarray) -> None:
        """The vacant options (order, vehicle id, pick-up distance) of the round just built at ``t``."""
        self._offered = (t, orders, vehicles, pickup_m)

    def observe(self, state: RoundState) -> None:
        """Record the pick-up times of the round's V1 passengers assigned in the previous round."""
        riders = state.v1_order
        new = riders[np.isnan(self.pick_s[riders])]
        if not len(new) or self._offered is None:
            return
        t_prev, orders, vehicles, pk = self._offered
        vehicle_of = dict(zip(riders.tolist(), state.v1_vehicle.tolist(), strict=True))
        key = {(int(o), int(v)): float(d) for o, v, d in zip(orders, vehicles, pk, strict=True)}
        for a in new.tolist():
            d = key.get((a, vehicle_of[a]))
            if d is None:
                continue
            self.pick_s[a] = t_prev + d / self.speed_mps
            self._observed.append(d / self.speed_mps)

    def mean_s(self) -> float:
        """The mean of the last 50 observed pick-up times (``default_s`` before any)."""
        recent = self._observed[-50:]
        return float(np.mean(recent)) if recent else self.default_s

    def of_v1(self, state: RoundState, a: np.ndarray) -> np.ndarray:
        """When each V1 passenger in ``a`` is (or was, in effect) picked up: A's vehicle is at arc length
        ``v (t - pick)`` along P_A from then on (unknown: ``t`` plus :meth:`mean_s`)."""
        t = state.t_s
        pos = np.full(len(self.pick_s), -1, np.int64)
        pos[state.v1_order] = np.arange(state.n_v1)
        k = pos[a]
        onboard = state.v1_onboard[k]
        driven = state.v1_delta_m[k] - state.v1_pre_m[k]
        known = self.pick_s[a]
        fallback = t + self.mean_s()
        return np.where(onboard, t - driven / self.speed_mps, np.where(np.isnan(known), fallback, known))
