"""RTV: request-trip-vehicle assignment (Alonso-Mora et al., PNAS 2017) for capacity 2.

docs/algorithms.md §3.3 (rpbench RTV-2), with the seed's distance-saving objective:

* RV graph: vacant vehicles within R̄ of a request; partially occupied
  vehicles whose POOL with the request is feasible.
* Trips: size 1 for every RV edge; size 2 ``{r1, r2}`` only for vacant
  vehicles, both pick-up orders x both drop orders (a sequence is feasible when
  ``pk1 = pre + l(x_v, o_first) <= R̄`` and POOL from ``h = o_first`` is
  feasible, which includes ``l(o_first, o_second) <= R̄`` unless
  ``rr_pickup_check=False``); the best sequence is kept.  A request-request
  edge is therefore necessary for every size-2 trip (R6).
* Value to maximise ``c_ko·|T| + e(T, v) - l^pk(T, v)`` with ``c_ko = R̄`` by
  default (A15); ``c_ko="large"`` (10⁶ m) serves as many requests as
  possible first; ``objective="gross"`` uses ``e - 10⁻³·l^pk`` instead of
  ``e - l^pk``.
* ILP: each vehicle and each request at most once — a
  :class:`~rpbench.model.TripPackingModel` solved by the preset's backend.
* Rebalancing (PNAS step d) is off by default (A17), as in the seed's code;
  ``rebalance=True`` sends the vacant vehicles left idle after the ILP towards
  the origins of the requests left unassigned, ``min(|V_idle|, |R_ko|)``
  vehicles by a minimum-total-distance assignment (the LP is totally
  unimodular; ``scipy.optimize.linear_sum_assignment`` solves it exactly).
* Reassignment of assigned-but-not-picked-up requests is not offered:
  assignments are final in rpbench's simulator (and in the seed's code), which
  the checker verifies.

Options: ``c_ko`` (metres or "large"), ``objective`` ("net" | "gross"),
``rr_pickup_check`` (bool), ``rv_top_k`` (int or None), ``order_rule``,
``rebalance`` (bool).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from rpbench.exceptions import ParameterError
from rpbench.geometry import pool
from rpbench.model import Structure, TripPackingModel, quantize
from rpbench.options import Range, option
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import VALUE_UNIT_M, join_options, vacant_options
from rpbench.strategies.myopic import PoolingOptions

LARGE_C_KO_M = 1e6
PICKUP_TIE_BREAK = 1e-3


@dataclass(frozen=True)
class RTVOptions(PoolingOptions):
    """RTV's options (docs/algorithms.md §3.3, A15-A17)."""

    c_ko: float | str | None = option(
        None,
        "value of serving a request, metres or 'large' (default R̄, A15)",
        choices=("large",),
        range=Range(0.0, LARGE_C_KO_M, "m"),  # 'large' is the top of the range
    )
    objective: str = option("net", "net: e - pick-up; gross: e - 1e-3 pick-up", choices=("net", "gross"))
    rr_pickup_check: bool = option(True, "size-2 trips need l(o_first, o_second) <= R̄")
    rv_top_k: int | None = option(
        None, "keep each request's k best vehicle edges (None: all)", range=Range(1, 10**6, integer=True)
    )
    rebalance: bool = option(False, "send idle vacant vehicles towards unassigned requests (PNAS step d, A17)")
    reassign: bool = option(False, "reassign assigned requests (not supported: assignments are final)")

    def __post_init__(self) -> None:
        if self.reassign:
            raise ParameterError("rtv reassign is not supported: assignments are final in rpbench's simulator")
        if self.rv_top_k is not None and self.rv_top_k <= 0:
            raise ParameterError(f"rtv rv_top_k {self.rv_top_k!r} must be a positive integer")


class RTV(Strategy[RTVOptions]):
    name = "rtv"
    label = "RTV"
    color = "tab:orange"
    structure = Structure.TRIP_PACKING
    description = "request-trip-vehicle ILP (PNAS 2017), capacity 2, distance-saving objective"
    Options = RTVOptions

    def c_ko(self, state: RoundState) -> float:
        c = self.options.c_ko
        if c is None:
            return state.params.max_pickup_m
        if c == "large":
            return LARGE_C_KO_M
        return float(c)

    def _net(self, saving_m: np.ndarray, pickup_m: np.ndarray) -> np.ndarray:
        weight = PICKUP_TIE_BREAK if self.options.objective == "gross" else 1.0
        return saving_m - weight * pickup_m

    def build(self, state: RoundState) -> RoundModel:
        c_ko = self.c_ko(state)
        vac = vacant_options(state)
        join = join_options(state, self.options.order_rule)
        # Size-1 trips: vacant (e = 0) and joins (e = POOL saving).
        cols = {
            "kind": [np.full(len(vac.p), Kind.VACANT), np.full(len(join.p), Kind.JOIN)],
            "vehicle_row": [vac.v, state.n_v0 + join.v],
            "r1": [vac.p, join.p],
            "r2": [np.full(len(vac.p), -1), np.full(len(join.p), -1)],
            "first": [vac.p, join.p],
            "fofo": [np.zeros(len(vac.p), bool), join.fofo],
            "value": [
                c_ko + self._net(np.zeros(len(vac.p)), vac.pickup_m),
                c_ko + self._net(join.saving_m, join.pickup_m),
            ],
            "pickup": [vac.pickup_m, join.pickup_m],
        }
        self._add_pair_trips(state, vac, c_ko, cols)
        merged = {k: np.concatenate(v) if v else np.zeros(0) for k, v in cols.items()}
        if self.options.rv_top_k is not None:
            merged = _top_k_per_request(merged, int(self.options.rv_top_k))
        vehicle_sim = (
            np.concatenate([state.v0_vehicle, state.v1_vehicle])[merged["vehicle_row"].astype(int)]
            if len(merged["vehicle_row"])
            else np.zeros(0, np.int64)
        )
        r1, r2 = merged["r1"].astype(np.int64), merged["r2"].astype(np.int64)
        order = np.lexsort((vehicle_sim, r2, r1))  # deterministic column order
        first = merged["first"].astype(np.int64)[order]
        second = np.where(r2[order] < 0, -1, np.where(first == r1[order], r2[order], r1[order]))
        model = TripPackingModel(
            state.n_passengers,
            state.n_v0 + state.n_v1,
            merged["vehicle_row"].astype(np.int64)[order],
            r1[order],
            r2[order],
            quantize(merged["value"][order], VALUE_UNIT_M),
            unit_m=VALUE_UNIT_M,
            name="rtv",
        )
        return RoundModel(
            model=model,
            kind=merged["kind"].astype(np.int8)[order],
            vehicle=vehicle_sim[order],
            first=state.p_order[first],
            second=np.where(second >= 0, state.p_order[np.maximum(second, 0)], -1),
            fofo=merged["fofo"].astype(bool)[order],
            utility_m=merged["value"][order],
            pickup_m=merged["pickup"][order],
        )

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """PNAS step (d): idle vacant vehicles towards unassigned requests, minimum total distance."""
        none = np.zeros(0, np.int64)
        if not self.options.rebalance or state.n_v0 == 0 or state.n_passengers == 0:
            return none, none
        served = np.isin(state.p_order, np.concatenate([rm.first[chosen], rm.second[chosen]]))
        busy = np.isin(state.v0_vehicle, rm.vehicle[chosen])
        requests = np.flatnonzero(~served)
        idle = np.flatnonzero(~busy)
        if len(requests) == 0 or len(idle) == 0:
            return none, none
        cost = (
            state.v0_pre_m[idle][:, None] + state.dist[state.v0_node[idle][:, None], state.p_origin[requests][None, :]]
        )
        rows, cols = linear_sum_assignment(cost)  # min(|idle|, |requests|) pairs, minimum total distance
        return state.v0_vehicle[idle[rows]].astype(np.int64), state.p_origin[requests[cols]].astype(np.int64)

    def _add_pair_trips(self, state: RoundState, vac, c_ko: float, cols: dict) -> None:
        """Size-2 trips on vacant vehicles: best of 4 sequences per (pair, vehicle)."""
        n = state.n_passengers
        if n < 2 or len(vac.p) == 0:
            return
        # Only passengers with a vacant vehicle within R̄ can share a size-2 trip, and only on a vehicle both
        # reach: POOL is asked about those pairs alone (half of all rider pairs on the full day), in the same
        # row-major order, and vehicles are numbered among the reached ones in increasing order, so the trips
        # come out exactly as from every pair on every vehicle.
        riders, rider = _present(vac.p, n)
        if len(riders) < 2:
            return
        fleet, vehicle = _present(vac.v, state.n_v0)
        pk = np.full((len(riders), len(fleet)), np.inf)
        pk[rider, vehicle] = vac.pickup_m  # RV edges only (others stay infinite)
        reach = np.isfinite(pk)
        reach_f = reach.astype(np.float64)
        shared = reach_f @ reach_f.T > 0  # a vehicle both reach (whole counts, exact)
        a, b = np.nonzero(np.triu(shared, k=1))  # pairs a < b, row-major
        if len(a) == 0:
            return
        i, j = riders[a], riders[b]
        rr_pickup = state.params.max_pickup_m if self.options.rr_pickup_check else np.inf
        # Direction i -> j (i picked up first) and j -> i; drop order chosen by POOL.
        fwd = pool(
            state.dist,
            state.p_origin[i],
            state.p_destination[i],
            state.p_origin[j],
            state.p_destination[j],
            max_pickup_m=rr_pickup,
            max_detour_m=state.params.max_detour_m,
            order_rule=self.options.order_rule,
        )
        bwd = pool(
            state.dist,
            state.p_origin[j],
            state.p_destination[j],
            state.p_origin[i],
            state.p_destination[i],
            max_pickup_m=rr_pickup,
            max_detour_m=state.params.max_detour_m,
            order_rule=self.options.order_rule,
        )
        edge = fwd.feasible | bwd.feasible  # the request-request edge
        if not edge.any():
            return
        a, b, i, j = a[edge], b[edge], i[edge], j[edge]
        fwd_ok, bwd_ok = fwd.feasible[edge], bwd.feasible[edge]
        fwd_e, bwd_e = fwd.saving[edge], bwd.saving[edge]
        fwd_fofo, bwd_fofo = fwd.fofo[edge], bwd.fofo[edge]
        e, v = np.nonzero(reach[a] & reach[b])
        pk_i, pk_j = pk[a[e], v], pk[b[e], v]
        val_f = np.where(fwd_ok[e], 2 * c_ko + self._net(fwd_e[e], pk_i), -np.inf)
        val_b = np.where(bwd_ok[e], 2 * c_ko + self._net(bwd_e[e], pk_j), -np.inf)
        take_f = val_f >= val_b  # tie -> the lower-index request first
        cols["kind"].append(np.full(len(e), Kind.TRIP2))
        cols["vehicle_row"].append(fleet[v])
        cols["r1"].append(i[e])
        cols["r2"].append(j[e])
        cols["first"].append(np.where(take_f, i[e], j[e]))
        cols["fofo"].append(np.where(take_f, fwd_fofo[e], bwd_fofo[e]))
        cols["value"].append(np.where(take_f, val_f, val_b))
        cols["pickup"].append(np.where(take_f, pk_i, pk_j))


def _present(index: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The distinct values of ``index`` (in ``0..size-1``) in increasing order, and each entry's rank among them.

    ``np.unique(index, return_inverse=True)`` by counting: it sorted, and cost more than POOL on small rounds.
    """
    present = np.zeros(size, dtype=bool)
    present[index] = True
    rank = np.cumsum(present) - 1
    return np.flatnonzero(present), rank[index]


def _top_k_per_request(cols: dict, k: int) -> dict:
    """Keep each request's k best size-1 RV edges (docs/algorithms.md §3.3 pruning); pair trips need both edges."""
    if k <= 0:
        raise ParameterError(f"rtv rv_top_k {k!r} must be a positive integer")
    single = cols["r2"] < 0
    idx = np.flatnonzero(single)
    order = idx[np.lexsort((-cols["value"][idx], cols["r1"][idx]))]
    rank = np.zeros(len(order), dtype=np.int64)
    if len(order):
        starts = np.flatnonzero(np.r_[True, np.diff(cols["r1"][order]) != 0])
        rank = np.arange(len(order)) - np.repeat(starts, np.diff(np.r_[starts, len(order)]))
    keep = np.zeros(len(single), dtype=bool)
    keep[order[rank < k]] = True
    kept_edges = {(int(r), int(v)) for r, v in zip(cols["r1"][keep], cols["vehicle_row"][keep], strict=True)}
    pair = ~single
    ok_pair = np.array(
        [
            (int(a), int(v)) in kept_edges and (int(b), int(v)) in kept_edges
            for a, b, v in zip(cols["r1"][pair], cols["r2"][pair], cols["vehicle_row"][pair], strict=True)
        ],
        dtype=bool,
    )
    keep[np.flatnonzero(pair)[ok_pair]] = True
    return {name: arr[keep] for name, arr in cols.items()}
