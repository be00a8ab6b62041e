"""The checker's own pair geometry and the ``bound-certificate`` check.

The geometry (POOL of docs/algorithms.md §1.1, the bound's graph of docs/bound.md) is written again here
from the folder's distance table, apart from :mod:`rpbench.geometry` and :mod:`rpbench.oracle.pairs`, so
that a fault there is not repeated in the verdict on its output.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.check.core import CERT_TOL_M, DETOUR_TOL_M, TOL_M, TOL_S, RunCheck
from rpbench.check.folder import Folder
from rpbench.network import Distances
from rpbench.scenarios.base import Params


# ---------------------------------------------------------------- pair geometry
@dataclass
class Geometry:
    """Both service orders of pairs with ``x`` picked up first and ``y`` joining: the vehicle turns towards
    o_y at node h after x rode ``delta`` metres, ``pre`` metres before h (POOL of docs/algorithms.md §1.1, written
    again here from the distance table)::

        FOFO (x dropped first): L = δ + l(h, o_y) + l(o_y, d_x) + l(d_x, d_y)
        FOLO (x dropped last):  L = δ + l(h, o_y) + l_y + l(d_y, d_x)
    """

    head: np.ndarray  # δ + l(h, o_y)
    pk: np.ndarray  # pre + l(h, o_y): y's pick-up distance
    l_oy_dx: np.ndarray
    l_dx_dy: np.ndarray
    fofo_len: np.ndarray
    folo_len: np.ndarray
    fofo_ok: np.ndarray  # both detours <= D̄
    folo_ok: np.ndarray
    l_x: np.ndarray
    l_y: np.ndarray

    @classmethod
    def of(
        cls,
        f: Folder,
        x: np.ndarray,
        y: np.ndarray,
        h: np.ndarray,
        delta: np.ndarray,
        pre: np.ndarray,
        max_detour_m: float,
    ) -> Geometry:
        dist, o, d, solo = f.distances.dist, f.col("origin"), f.col("destination"), f.solo
        p = dist[h, o[y]]
        l_oy_dx, l_dx_dy, l_dy_dx = dist[o[y], d[x]], dist[d[x], d[y]], dist[d[y], d[x]]
        head = delta + p
        fofo_len = head + l_oy_dx + l_dx_dy
        folo_len = head + solo[y] + l_dy_dx
        lim = max_detour_m + DETOUR_TOL_M
        return cls(
            head=head,
            pk=pre + p,
            l_oy_dx=l_oy_dx,
            l_dx_dy=l_dx_dy,
            fofo_len=fofo_len,
            folo_len=folo_len,
            fofo_ok=(head + l_oy_dx - solo[x] <= lim) & (l_oy_dx + l_dx_dy - solo[y] <= lim),
            folo_ok=folo_len - solo[x] <= lim,
            l_x=solo[x],
            l_y=solo[y],
        )

    def rule_order(self, rule: str) -> np.ndarray:
        """FOFO? as the order rule picks: the feasible order with the smaller L (tie: FOFO), or the smaller L."""
        if rule == "min_then_check":
            return self.fofo_len <= self.folo_len
        return self.fofo_ok & (~self.folo_ok | (self.fofo_len <= self.folo_len))

    def served(self, fofo: np.ndarray) -> dict[str, np.ndarray]:
        """Lengths, rides, detours, shared distance and saving in the service order ``fofo``."""
        length = np.where(fofo, self.fofo_len, self.folo_len)
        ride_x = np.where(fofo, self.head + self.l_oy_dx, length)
        ride_y = np.where(fofo, self.l_oy_dx + self.l_dx_dy, self.l_y)
        return {
            "ok": np.where(fofo, self.fofo_ok, self.folo_ok),
            "length": length,
            "detour_x": ride_x - self.l_x,
            "detour_y": ride_y - self.l_y,
            "shared": np.where(fofo, self.l_oy_dx, self.l_y),
            "pk": self.pk,
            "saving": self.l_x + self.l_y - length,
        }


def order_paths(f: Folder, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shortest path of each order ``x`` (as the simulator drives it), flattened: ``(offsets, nodes,
    cum)`` with ``cum`` the distance from the order's origin to each node."""
    o, d = f.col("origin"), f.col("destination")
    unique, inverse = np.unique(x, return_inverse=True)
    if not len(unique):
        return np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)
    off_u, nodes_u = f.distances.paths_batch(o[unique], d[unique])
    lengths = np.diff(off_u)[inverse]
    offsets = np.r_[0, np.cumsum(lengths)].astype(np.int64)
    within = np.arange(offsets[-1]) - np.repeat(offsets[:-1], lengths)
    nodes = nodes_u[np.repeat(off_u[:-1][inverse], lengths) + within].astype(np.int64)
    cum = f.distances.dist[np.repeat(o[x], lengths), nodes]
    return offsets, nodes, cum


def first_true(mask: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Flat index of the first True of each segment ``[offsets[i], offsets[i+1])``; -1 where there is none."""
    hits = np.flatnonzero(mask)
    pos = np.searchsorted(hits, offsets[:-1])
    cand = hits[np.minimum(pos, len(hits) - 1)] if len(hits) else np.zeros(len(offsets) - 1, np.int64)
    return np.where((pos < len(hits)) & (cand < offsets[1:]), cand, -1)


def all_paths(f: Folder) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every order's shortest path, once (:func:`order_paths` of every order): order ``i``'s nodes are
    ``nodes[offsets[i]:offsets[i + 1]]``."""
    return order_paths(f, np.arange(f.n))


def turning_points(
    f: Folder, params: Params, x: np.ndarray, y: np.ndarray, paths: tuple | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """docs/bound.md's orientation "x first, y joins": (allowed, h*, δ = l(o_x, h*)); ``paths`` from
    :func:`all_paths` (None: the paths of the orders ``x`` alone are found).

    Allowed: ``t_y - t_x`` in ``[-K_y, K_x + (R̄ + l_x)/v]``, and h*, the first node of x's shortest path
    within R̄ of o_y at or beyond the least distance x's vehicle has driven when y is revealed,
    ``v (t_y - t_x - K_x) - R̄`` (x picked up by ``t_x + K_x + R̄/v``), exists with its predecessor within
    ``v (t_y + K_y - t_x)`` of o_x.  The arc lengths along a path only grow, so both limits are found by
    binary search and only the nodes between them are tested, one vectorised step per node, each pair
    leaving at its first node within R̄: O(log ℓ + the nodes tested) a pair.
    """
    t, k, origin = f.col("request_s"), f.col("patience_s"), f.col("origin")
    v, r_max = params.speed_mps, params.max_pickup_m
    if paths is None:
        unique = np.unique(x)
        offsets, nodes, cum = order_paths(f, unique)
        slot = np.searchsorted(unique, x)
    else:
        (offsets, nodes, cum), slot = paths, x
    gap = t[y] - t[x]
    allowed = (-k[y] - TOL_S <= gap) & (gap <= k[x] + (r_max + TOL_M + f.solo[x]) / v + TOL_S)
    h = origin[x].astype(np.int64)
    delta = np.zeros(len(x))
    rows = np.flatnonzero(allowed)
    xs, oy, start, end = x[rows], origin[y[rows]], offsets[slot[rows]], offsets[slot[rows] + 1]
    driven = v * (gap[rows] - k[xs] - TOL_S) - (r_max + TOL_M)  # at least, once y is revealed
    reach = v * (t[y[rows]] + k[y[rows]] - t[xs]) + TOL_M
    # nodes p >= lo (cum >= driven) whose predecessor is within reach (p == start, or cum[p - 1] <= reach)
    pos = _search(cum, start, end, driven, right=False)
    last = np.minimum(_search(cum, start, end, reach, right=True), end - 1)
    found = np.full(len(rows), -1, np.int64)
    active = np.flatnonzero(pos <= last)
    while len(active):
        p = pos[active]
        hit = f.distances.dist[nodes[p], oy[active]] <= r_max + TOL_M
        found[active[hit]] = p[hit]
        go = ~hit & (p < last[active])
        pos[active[go]] += 1
        active = active[go]
    ok = found >= 0
    allowed[rows[~ok]] = False
    h[rows[ok]] = nodes[found[ok]]
    delta[rows[ok]] = cum[found[ok]]
    return allowed, h, delta


def _search(cum: np.ndarray, lo: np.ndarray, hi: np.ndarray, value: np.ndarray, right: bool) -> np.ndarray:
    """Per segment ``[lo, hi)`` of the non-decreasing ``cum``: the first index with ``cum >= value`` (``cum >
    value`` when ``right``), ``hi`` where there is none.  A vectorised binary search."""
    lo, hi = lo.copy(), hi.copy()
    top = max(len(cum) - 1, 0)
    while True:
        active = lo < hi
        if not active.any():
            return lo
        mid = (lo + hi) // 2
        c = cum[np.minimum(mid, top)]
        below = active & ((c <= value) if right else (c < value))
        lo = np.where(below, mid + 1, lo)
        hi = np.where(active & ~below, mid, hi)


def bound_geometry(
    f: Folder, params: Params, x: np.ndarray, y: np.ndarray, paths: tuple | None = None
) -> tuple[np.ndarray, Geometry]:
    """docs/bound.md's orientation "x first, y joins": (allowed, geometry with the vehicle at h*), h* as
    :func:`turning_points` finds it."""
    allowed, h, delta = turning_points(f, params, x, y, paths)
    return allowed, Geometry.of(f, x, y, h, delta, np.zeros(len(x)), params.max_detour_m)


def _orientation_weight(f: Folder, x: np.ndarray, y: np.ndarray, paths: tuple | None = None) -> np.ndarray:
    """Per pair, the saving with x first and y joining under the bound's rule (the feasible service order
    with the smaller route), or -inf where that orientation is not allowed.  The routes are valued only
    for the allowed pairs."""
    allowed, h, delta = turning_points(f, f.params, x, y, paths)
    out = np.full(len(x), -np.inf)
    k = np.flatnonzero(allowed)
    g = Geometry.of(f, x[k], y[k], h[k], delta[k], np.zeros(len(k)), f.params.max_detour_m)
    r = g.served(g.rule_order("min_feasible"))
    out[k] = np.where(r["ok"], r["saving"], -np.inf)
    return out


def edge_weights(f: Folder, a: np.ndarray, b: np.ndarray, a_first_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(weight, edge) of pairs (a, b) in the upper bound's graph: the largest saving over the allowed
    orientations (only "a first": ``a_first_only``); ``edge`` is False (weight -inf) when none is allowed."""
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    weight = _orientation_weight(f, a, b)
    if not a_first_only:
        weight = np.fmax(weight, _orientation_weight(f, b, a))
    return weight, np.isfinite(weight)


def bound_weights(
    distances: Distances,
    orders: pd.DataFrame,
    solo: np.ndarray,
    params: Params,
    a: np.ndarray,
    b: np.ndarray,
    a_first_only: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """(weight, edge) of pairs (a, b) in the upper bound's graph (docs/bound.md), computed here, apart from
    the enumeration of rpbench.oracle.pairs.  ``distances`` is the network's Distances; ``orders``
    holds request_s, patience_s, origin and destination."""
    f = Folder(
        Path("."),
        {},
        params,
        orders,
        pd.DataFrame(),
        distances.network,
        distances,
        np.asarray(solo, dtype=np.float64),
        pd.DataFrame(),
    )
    return edge_weights(f, a, b, a_first_only)


# ------------------------------------------------------------ bound certificate
def check_certificate(rc: RunCheck, tab: pd.DataFrame, f: Folder, saving_km: float, bound_km: float | None) -> None:
    """Every pair of the run is a bound edge whose weight covers its realised saving; saving <= bound."""
    partner, ok = tab["partner"].to_numpy(), tab["ok"].to_numpy()
    t_pick = tab["pickup_s"].to_numpy()
    both = (partner >= 0) & ok & ok[np.maximum(partner, 0)]
    me = np.flatnonzero(both)
    first_me = (t_pick[me] < t_pick[partner[me]]) | ((t_pick[me] == t_pick[partner[me]]) & (me < partner[me]))
    a = me[first_me]  # picked up first
    b = partner[a]
    odo_pick, odo_drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    occupied = np.maximum(odo_drop[a], odo_drop[b]) - odo_pick[a]
    realised = f.solo[a] + f.solo[b] - occupied
    own = _orientation_weight(f, a, b)  # the run's pick-up order, computed once
    weight = np.fmax(own, _orientation_weight(f, b, a))
    edge, own_edge = np.isfinite(weight), np.isfinite(own)
    for k in np.flatnonzero(~own_edge)[:5]:
        rc.fail(
            "bound-certificate",
            f"pair ({a[k]}, {b[k]}) is not an edge of the upper bound's graph with "
            f"order {a[k]} first (time window or detours at its origin)",
        )
    over = edge & (realised > weight + CERT_TOL_M)
    for k in np.flatnonzero(over)[:5]:
        rc.fail(
            "bound-certificate",
            f"pair ({a[k]}, {b[k]}): realised saving {realised[k]:.3f} m exceeds the "
            f"bound's edge weight {weight[k]:.3f} m",
        )
    rc.checked["certified_pairs"] = int((own_edge & ~over).sum())
    if bound_km is None:
        return
    if not np.isfinite(bound_km):
        rc.fail("bound-certificate", "the folder's upper bound is not finite (its solver proved no bound)")
    elif saving_km > bound_km + CERT_TOL_M / 1000.0 * max(1, len(a)):
        rc.fail("bound-certificate", f"saving {saving_km:.3f} km exceeds the upper bound {bound_km:.3f} km")
