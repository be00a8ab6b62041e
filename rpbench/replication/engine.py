"""The authors' simulator semantics as a second engine (issue 13), each mechanism behind a switch.

This is a re-implementation from reading the authors' public code (no code
copied): a batch round every 10 s releases the passengers who requested in
(t - 10 s, t], offers every free vehicle (vacant, or carrying one passenger =
a *taker*) to every waiting passenger, solves one assignment, then moves the
fleet.  What differs from rpbench's own simulator (``rpbench/sim``, which this
module never touches) is listed in :mod:`rpbench.replication.switches`; each
difference is a switch of :class:`Switches`, all on by default.

The engine uses rpbench's building blocks: the network's all-pairs distances
(:class:`~rpbench.network.DistanceOracle`), the solver-agnostic
:class:`~rpbench.model.AssignmentModel` solved by any preset, and the
scenario's orders and fleet.  It writes no event log for rpbench's checker:
teleporting vehicles have no trajectory to check; :mod:`rpbench.results.replication_audit`
re-checks what still applies (assignment and accounting).
"""

from __future__ import annotations

import itertools
import random
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rpbench.backends.presets import Preset
from rpbench.backends.solve import solve
from rpbench.exceptions import ParameterError
from rpbench.model import AssignmentModel, quantize
from rpbench.replication import weights as W
from rpbench.replication.cells import NO_CELL, node_cells
from rpbench.replication.rtv import build_round as build_rtv_round
from rpbench.replication.rtv import pair_geometry as rtv_geometry
from rpbench.replication.switches import Switches
from rpbench.scenarios.base import Scenario

STRATEGIES = ("np", "mb", "rtv", "fl-nd", "fl")
#: Strategies whose authors' code returns before moving anyone in a round without passengers or free vehicles.
EARLY_RETURN = ("mb", "fl-nd", "fl")
SECONDS_PER_M = 0.12  # the authors' unit_driving_time (30 km/h)
DT_S = 10.0
SOLO_TIMEOUT_S = 600.0
AUTHORS_PATIENCE_CONST_S = 90.0


@dataclass
class Leg:
    """A vehicle driving its shortest route(s) from ``start_s``: node sequence and arrival time at each node."""

    start_s: float
    nodes: np.ndarray
    at_s: np.ndarray
    metres: np.ndarray

    def index_at(self, t: float) -> int:
        return int(np.searchsorted(self.at_s, t, side="right") - 1)

    def node_at(self, t: float) -> int:
        return int(self.nodes[max(0, self.index_at(t))])

    @property
    def end_s(self) -> float:
        return float(self.at_s[-1])


@dataclass
class Vehicle:
    node: int
    active_at: float = 0.0  # the authors' activate_time: free again when t > active_at
    p0: int = -1  # the passenger of a taker, -1 when vacant
    picked: bool = False
    pickup_s: float = np.nan  # proper movement: when p0 boards
    arrive_s: float = np.nan  # proper movement: when p0 reaches the destination
    assigned_s: float = 0.0
    assign_node: int = -1
    p0_pickup_m: float = 0.0  # the authors' ledger of p0's pick-up
    leg: Leg | None = None
    idle_route: list[int] = field(default_factory=list)  # teleport: nodes still to visit, taken from the end
    idle_first_m: float = 0.0  # teleport: first link of the idle route (the authors' waiting test)
    reposition_s: float = 0.0


@dataclass
class Record:
    """One served passenger, as the authors' history keeps it."""

    order: int
    vehicle: int
    assign_s: float
    wait_s: float
    pickup_m: float
    pooled: bool = False
    partner: int = -1
    detour_m: float = np.nan
    shared_m: float = np.nan
    ride_m: float = np.nan


@dataclass
class Outcome:
    """A run of the engine: served passengers, pairs, and the KPIs in the authors' definitions."""

    strategy: str
    switches: Switches
    records: list[Record]
    pair_saving_m: list[float]
    shared_m: list[float]
    denominator: int
    n_orders: int
    n_vehicles: int
    rounds: int
    wall_s: float
    assigned: list[tuple[int, int, float]] = field(default_factory=list)  # (order, vehicle, t)
    scenario_orders: object = None  # the scenario's Orders (record ``order`` indexes them)
    patience_s: np.ndarray | None = None  # the patience the engine applied (floored or not)
    solo_m: np.ndarray | None = None

    def passengers(self) -> pd.DataFrame:
        return pd.DataFrame([r.__dict__ for r in self.records])

    def kpis(self) -> dict[str, float]:
        served = len({r.order for r in self.records})
        pooled = [r for r in self.records if r.pooled]
        return {
            "orders": self.n_orders,
            "response_denominator": self.denominator,
            "vehicles": self.n_vehicles,
            "served": served,
            "pooled_passengers": len(pooled),
            "response_rate": served / self.denominator if self.denominator else float("nan"),
            "pairing_ratio": len(pooled) / served if served else float("nan"),
            "total_saving_km": float(np.sum(self.pair_saving_m)) / 1000.0,
            "avg_detour_m": float(np.mean([r.detour_m for r in pooled])) if pooled else float("nan"),
            "avg_shared_m": float(np.mean(self.shared_m)) if self.shared_m else float("nan"),
            "avg_response_time_s": float(np.mean([r.wait_s for r in self.records])) if self.records else float("nan"),
            "avg_pickup_time_s": (
                SECONDS_PER_M * float(np.mean([r.pickup_m for r in self.records])) if self.records else float("nan")
            ),
            "wall_s": self.wall_s,
        }


class AuthorsEngine:
    """Simulate one strategy on one scenario under ``switches``.

    ``predictions`` (FL, FL-no_delay) holds per order the columns
    ``saved_distance_for_seeker`` and ``saved_distance_for_taker`` aligned with
    ``scenario.orders``; ``denominator`` is the response-rate denominator
    (default: the released orders).  ``reposition_origins`` is the list idle
    vehicles draw targets from (default: the released orders' distinct
    origins); ``release_rank`` (one integer per order) orders each round's new
    passengers (default: request time) -- the authors list them in their
    sample's row order, which decides who is "first" in an RTV pair edge.
    """

    def __init__(
        self,
        scenario: Scenario,
        strategy: str,
        preset: Preset,
        *,
        switches: Switches | None = None,
        predictions: pd.DataFrame | None = None,
        denominator: int | None = None,
        reposition_origins: np.ndarray | None = None,
        release_rank: np.ndarray | None = None,
    ):
        if strategy not in STRATEGIES:
            raise ParameterError(f"the authors' engine runs {', '.join(STRATEGIES)}; not {strategy!r}")
        self.sc = scenario
        self.strategy = strategy
        self.preset = preset
        self.sw = switches or Switches()
        self.dist = scenario.network.distances()
        orders = scenario.orders
        self.o, self.d = orders.origin.astype(np.int64), orders.destination.astype(np.int64)
        self.req = orders.request_s
        self.solo = self.dist.dist[self.o, self.d]
        floor = 30.0 if (strategy in ("fl", "rtv") or not self.sw.authors_weights) else 0.0
        self.patience = np.maximum(orders.patience_s, floor)
        self.e_seeker, self.e_taker = self._predictions(predictions)
        self.flp = W.fl_params(self.sw.authors_ledger)
        self.denominator = int(denominator if denominator is not None else len(orders))
        self.cell = node_cells(scenario.network.lon, scenario.network.lat) if self.sw.grid_cells else None
        self.vehicles = [Vehicle(node=int(n)) for n in scenario.fleet.initial_node]
        # The authors draw idle targets from the sampled origins with Python's global random state, last
        # seeded by the fleet placement (random.seed(n - 1) followed by one choice).
        self.idle_origins = (
            np.asarray(reposition_origins) if reposition_origins is not None else np.asarray(pd.unique(self.o))
        )
        self.rng = random.Random(len(self.vehicles) - 1)
        self.rng.choice(list(self.idle_origins))
        self.release_rank = None if release_rank is None else np.asarray(release_rank, dtype=np.int64)
        if self.release_rank is not None and len(self.release_rank) != len(orders):
            raise ParameterError(f"release_rank has {len(self.release_rank)} entries for {len(orders)} orders")
        self.records: list[Record] = []
        self.pair_saving: list[float] = []
        self.shared: list[float] = []
        self.assigned: list[tuple[int, int, float]] = []
        self.responded = np.zeros(len(orders), dtype=bool)
        self.k = np.zeros(len(orders))
        self.fresh = np.ones(len(orders), dtype=bool)

    # ------------------------------------------------------------ inputs
    def _predictions(self, predictions: pd.DataFrame | None) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.sc.orders)
        if self.strategy not in ("fl", "fl-nd"):
            return np.zeros(n), np.zeros(n)
        if predictions is None or not {"saved_distance_for_seeker", "saved_distance_for_taker"} <= set(predictions):
            raise ParameterError(
                f"strategy {self.strategy!r} under the authors' engine needs the per-order "
                "predictions of the order files (use the haikou-paper-input scenario)"
            )
        seeker = predictions["saved_distance_for_seeker"].to_numpy(dtype=float)
        taker = predictions["saved_distance_for_taker"].to_numpy(dtype=float)
        if np.isnan(seeker).any() or np.isnan(taker).any():
            raise ParameterError("some orders have no prediction for their OD pair")
        scale = 2.0 if self.sw.authors_ledger else 1.0  # the authors double both when loading
        return scale * seeker, scale * taker

    def dist_m(self, a, b):
        """Shortest distance a -> b (m), vectorised."""
        return self.dist.dist[a, b]

    # ------------------------------------------------------------ the loop
    def run(self) -> Outcome:
        t0 = time.perf_counter()
        waiting: list[int] = []
        released = 0
        n = len(self.req)
        rounds = 0
        t = DT_S
        while t < self.sc.horizon_s:  # the authors stop at 09:00:00 without a last round
            rounds += 1
            new_end = int(np.searchsorted(self.req, t, side="right"))
            new = [i for i in range(released, new_end) if self.req[i] > t - DT_S]
            if self.release_rank is not None:
                new.sort(key=lambda i: self.release_rank[i])
            released = new_end
            seekers = new + waiting
            for i in new:
                self.fresh[i] = True
            self._advance_proper(t)
            active = [v for v, veh in enumerate(self.vehicles) if t > veh.active_at]
            if self.sw.teleport and self.strategy in EARLY_RETURN and (not seekers or not active):
                # The authors return before moving anyone, and keep passengers with a fixed 90 s patience.
                waiting = [i for i in seekers if not self.responded[i] and t - self.req[i] < AUTHORS_PATIENCE_CONST_S]
                self._mark_waiting(waiting, t)
                t += DT_S
                continue
            if not (seekers and active):
                matches = {}
            elif self.strategy == "rtv":
                matches = self._match_rtv(t, seekers, active)
            else:
                matches = self._match(t, seekers, active)
            self._apply(t, matches, active)
            waiting = [i for i in seekers if not self.responded[i] and t - self.req[i] < self.patience[i]]
            self._mark_waiting(waiting, t)
            t += DT_S
        return Outcome(
            strategy=self.strategy,
            switches=self.sw,
            records=self.records,
            pair_saving_m=self.pair_saving,
            shared_m=self.shared,
            denominator=self.denominator,
            n_orders=n,
            n_vehicles=len(self.vehicles),
            rounds=rounds,
            wall_s=time.perf_counter() - t0,
            assigned=self.assigned,
            scenario_orders=self.sc.orders,
            patience_s=self.patience,
            solo_m=self.solo,
        )

    def _mark_waiting(self, waiting: list[int], t: float) -> None:
        for i in waiting:
            self.k[i] = np.floor((t - self.req[i]) / DT_S)
            self.fresh[i] = False

    # ------------------------------------------------------------ matching
    def _taker_geometry(self, veh: Vehicle, b: np.ndarray) -> dict[str, np.ndarray]:
        """Pick-up, in-vehicle distances, saving and detours of taker ``veh`` taking passengers ``b``."""
        a = veh.p0
        oa, da, la = self.o[a], self.d[a], self.solo[a]
        ob, db, lb = self.o[b], self.d[b], self.solo[b]
        if self.sw.pickup_from_first_origin:
            pk_weight = self.dist_m(ob, oa)  # the authors' weight: passenger origin -> first origin
            lead = self.dist_m(oa, ob)  # the ledger: first origin -> second origin
        else:
            x = veh.node
            if veh.picked:
                lead = self.dist_m(oa, x) + self.dist_m(x, ob)  # p0 has ridden O_a -> x along its shortest route
                pk_weight = self.dist_m(x, ob)
            else:
                lead = self.dist_m(oa, ob)
                pk_weight = self.dist_m(x, oa) + self.dist_m(oa, ob)
        f1, f2 = self.dist_m(ob, da), self.dist_m(da, db)
        l1, l2 = lb, self.dist_m(db, da)
        fofo = (f1 + f2 < l1 + l2) if self.sw.pickup_from_first_origin else (f1 + f2 <= l1 + l2)
        a_in = np.where(fofo, lead + f1, lead + l1 + l2)
        b_in = np.where(fofo, f1 + f2, l1)
        shared = np.where(fofo, f1, l1)
        saving = la + lb - (a_in + b_in - shared)
        return {
            "pk": pk_weight,
            "lead": lead,
            "fofo": fofo,
            "a_in": a_in,
            "b_in": b_in,
            "shared": shared,
            "saving": saving,
            "detour_a": a_in - la,
            "detour_b": b_in - lb,
            "rest": np.where(fofo, f1 + f2, l1 + l2),
        }

    def _match(self, t: float, seekers: list[int], active: list[int]) -> dict[int, int]:
        p = self.sc.params
        s = np.asarray(seekers, dtype=np.int64)
        k = self.k[s]
        fresh = self.fresh[s]
        prio = W.priority(k, fresh, self.flp)
        cols_p, cols_v, vals = [], [], []
        authors = self.sw.authors_weights
        off = W.offset(self.strategy, authors)
        col_of = {vi: c for c, vi in enumerate(active)}
        origin_cell = self.cell[self.o[s]] if self.cell is not None else None
        # Vacant vehicles, all at once (a vehicles x passengers block).
        vacant = [vi for vi in active if self.vehicles[vi].p0 < 0]
        if vacant:
            nodes = np.asarray([self.vehicles[vi].node for vi in vacant], dtype=np.int64)
            if self.strategy == "np" or not self.sw.pickup_from_first_origin:
                pk = self.dist.dist[nodes[:, None], self.o[s][None, :]]  # vehicle -> origin
            else:
                pk = self.dist.dist[self.o[s][None, :], nodes[:, None]]  # the authors' reversed direction
            ok = pk <= p.max_pickup_m
            if origin_cell is not None:
                vcell = self.cell[nodes]
                ok &= (vcell[:, None] == origin_cell[None, :]) & (vcell[:, None] != NO_CELL)
            value = W.vacant_values(
                self.strategy, authors, pk, self.solo[s][None, :], self.e_taker[s][None, :], prio[None, :]
            )
            rows, cols = np.nonzero(ok)
            cols_p.extend(cols.tolist())
            cols_v.extend(col_of[vacant[r]] for r in rows.tolist())
            vals.extend((value[rows, cols] + off).tolist())
        for vi in active:
            veh = self.vehicles[vi]
            if veh.p0 < 0 or self.strategy == "np":
                continue
            ok = np.ones(len(s), dtype=bool)
            if origin_cell is not None:
                ok &= (origin_cell == self.cell[veh.node]) & (self.cell[veh.node] != NO_CELL)
            g = self._taker_geometry(veh, s)
            ok &= (g["pk"] <= p.max_pickup_m) & (g["detour_a"] <= p.max_detour_m) & (g["detour_b"] <= p.max_detour_m)
            if self.strategy == "fl":
                ok &= g["saving"] >= 0
            v = W.taker_values(self.strategy, authors, g["saving"], g["pk"], prio)
            idx = np.flatnonzero(ok)
            cols_p.extend(idx.tolist())
            cols_v.extend([col_of[vi]] * len(idx))
            vals.extend((v[idx] + off).tolist())
        wait = W.wait_values(self.strategy, authors, self.e_seeker[s], np.where(fresh, 1.0, k), self.flp)
        cols_p.extend(range(len(s)))
        cols_v.extend([-1] * len(s))
        vals.extend(wait.tolist())
        model = AssignmentModel(len(s), len(active), cols_p, cols_v, quantize(vals), name="authors-round")
        sol = solve(model, self.preset)
        out: dict[int, int] = {}
        for c in sol.chosen:
            if model.col_vehicle[c] >= 0:
                out[active[int(model.col_vehicle[c])]] = int(s[model.col_passenger[c]])
        return out

    def _timed_out(self, veh: Vehicle, t: float) -> bool:
        """The authors deliver a taker alone 600 s after the request (less its pick-up time)."""
        return self.sw.authors_weights and t - self.req[veh.p0] - SECONDS_PER_M * veh.p0_pickup_m > SOLO_TIMEOUT_S

    def _taker_geometry_one(self, veh: Vehicle, b: int, *, from_vehicle: bool) -> dict[str, float]:
        """One passenger's pair geometry as floats; ``from_vehicle`` (with the authors' pick-up rule): the
        authors' RTV test measured from the vehicle's node, without the first passenger's ridden distance."""
        if from_vehicle and self.sw.pickup_from_first_origin:
            lead = float(self.dist_m(veh.node, self.o[b]))
            g = rtv_geometry(self.dist.dist, self.o, self.d, self.solo, veh.p0, b, lead, True)
            g["pk"] = lead
            return g
        g = self._taker_geometry(veh, np.asarray([b]))
        return {key: float(np.asarray(val).ravel()[0]) for key, val in g.items()}

    def _match_rtv(self, t: float, seekers: list[int], active: list[int]) -> dict[int, tuple[int, ...]]:
        model, decode = build_rtv_round(self, t, seekers, active)
        if model.n_cols == 0:
            return {}
        sol = solve(model, self.preset)
        return {decode[int(c)][0]: decode[int(c)][1] for c in sol.chosen}

    # ------------------------------------------------------------ commit and move
    def _apply(self, t: float, matches: dict[int, int], active: list[int]) -> None:
        for vi in active:
            veh = self.vehicles[vi]
            trip = matches.get(vi)
            if isinstance(trip, tuple) and len(trip) == 2:
                for r in trip:
                    self.responded[r] = True
                    self.assigned.append((r, vi, t))
                self._dispatch_two(vi, veh, trip, t)
                continue
            b = trip[0] if isinstance(trip, tuple) else trip
            if b is not None:
                self.responded[b] = True
                self.assigned.append((b, vi, t))
                if veh.p0 >= 0:
                    self._dispatch_pair(vi, veh, b, t)
                else:
                    self._take_first(vi, veh, b, t)
                    if self.strategy == "rtv" and self.sw.teleport:
                        self._rtv_first_move(vi, veh, t)
            elif veh.p0 >= 0:
                self._move_taker(vi, veh, t)
            else:
                self._idle(veh, t)

    def _take_first(self, vi: int, veh: Vehicle, b: int, t: float) -> None:
        pickup_m = self.dist_m(veh.node, self.o[b])
        if self.strategy == "np":
            # The authors' NP: jump to the destination, blocked for the real pick-up and ride.
            done = t + SECONDS_PER_M * (pickup_m + self.solo[b])
            self.records.append(Record(b, vi, t, t - self.req[b], pickup_m, ride_m=self.solo[b]))
            veh.node, veh.active_at, veh.leg, veh.idle_route = int(self.d_node(b)), done, None, []
            return
        veh.p0, veh.picked, veh.assigned_s, veh.assign_node = b, False, t, veh.node
        veh.p0_pickup_m = 0.0
        veh.idle_route, veh.leg = [], None
        if not self.sw.authors_ledger:
            self.records.append(Record(b, vi, t, t - self.req[b], pickup_m, ride_m=self.solo[b]))
        if not self.sw.teleport:
            veh.leg = self._leg(t, [veh.node, int(self.o[b]), int(self.d[b])])
            veh.pickup_s = t + SECONDS_PER_M * pickup_m
            veh.arrive_s = veh.leg.end_s
            veh.p0_pickup_m = pickup_m
        elif veh.node == int(self.o[b]):
            # The authors note the vehicle's node as its "origin" when they assign it; standing at the
            # passenger's origin, it counts as having picked the passenger up, its activity time left as it
            # was (no round spent boarding, no reset to this round).
            veh.picked = True

    def _rtv_first_move(self, vi: int, veh: Vehicle, t: float) -> None:
        """The authors' RTV moves a vehicle in the round it is assigned, unless it already stood at the
        passenger's origin (:meth:`_take_first` counted that as the pick-up, activity time kept)."""
        if not veh.picked:
            self._move_taker(vi, veh, t)

    def d_node(self, b: int) -> int:
        return int(self.d[b])

    def _leg(self, t: float, stops: list[int]) -> Leg:
        nodes = [stops[0]]
        for a, b in itertools.pairwise(stops):
            path = self.dist.path_nodes(a, b)
            nodes.extend(int(x) for x in path[1:])
        nodes_arr = np.asarray(nodes, dtype=np.int64)
        step = self.dist.dist[nodes_arr[:-1], nodes_arr[1:]] if len(nodes_arr) > 1 else np.zeros(0)
        metres = np.concatenate([[0.0], np.cumsum(step)])
        return Leg(t, nodes_arr, t + SECONDS_PER_M * metres, metres)

    def _dispatch_pair(self, vi: int, veh: Vehicle, b: int, t: float) -> None:
        a = veh.p0
        # Geometry as the matching saw it (before the vehicle is moved to O_a).
        g = self._taker_geometry(veh, np.asarray([b]))
        g = {key: float(np.asarray(val).ravel()[0]) for key, val in g.items()}
        if not veh.picked:
            # The authors put the vehicle at O_a; its pick-up distance grows by the whole remaining way
            # (which, with the second pick-up measured from O_a, does not delay the pair).  Driving by the
            # clock, the whole pick-up was booked at assignment already.
            if self.sw.teleport:
                veh.p0_pickup_m += float(self.dist_m(veh.node, self.o[a]))
            veh.picked = True
        pk_b = g["lead"] if self.sw.pickup_from_first_origin else g["pk"]
        saving = g["saving"]
        self.pair_saving.append(saving)
        self.shared.append(g["shared"])
        wait_a = self._first_wait(a)
        if self.sw.authors_ledger or not self._recorded(a):
            self.records = [r for r in self.records if r.order != a]
            self.records.append(
                Record(a, vi, veh.assigned_s, wait_a, veh.p0_pickup_m, True, b, g["detour_a"], g["shared"], g["a_in"])
            )
        else:
            self._update_record(
                a, pooled=True, partner=b, detour_m=g["detour_a"], shared_m=g["shared"], ride_m=g["a_in"]
            )
        self.records.append(Record(b, vi, t, t - self.req[b], pk_b, True, a, g["detour_b"], g["shared"], g["b_in"]))
        route_m = pk_b + g["rest"]
        veh.active_at = t + SECONDS_PER_M * route_m
        if self.sw.pickup_from_first_origin:
            veh.node = int(self.d[b])
        else:
            veh.node = int(self.d[b]) if g["fofo"] else int(self.d[a])
        veh.p0, veh.picked, veh.leg, veh.p0_pickup_m, veh.idle_route = -1, False, None, 0.0, []

    def _dispatch_two(self, vi: int, veh: Vehicle, trip: tuple[int, ...], t: float) -> None:
        """RTV: a vacant vehicle takes two passengers at once; the earlier request is picked up first."""
        a, b = trip if self.req[trip[0]] <= self.req[trip[1]] else (trip[1], trip[0])
        pickup = float(self.dist_m(veh.node, self.o[a]))
        between = float(self.dist_m(self.o[a], self.o[b]))
        # The authors count the vehicle's pick-up as the first passenger's ride and leave O_a -> O_b out.
        lead = pickup if self.sw.pickup_from_first_origin else between
        g = rtv_geometry(self.dist.dist, self.o, self.d, self.solo, a, b, lead, self.sw.pickup_from_first_origin)
        self.pair_saving.append(g["saving"])
        self.shared.append(g["shared"])
        self.records.append(Record(a, vi, t, t - self.req[a], pickup, True, b, g["detour_a"], g["shared"], g["a_in"]))
        self.records.append(Record(b, vi, t, t - self.req[b], between, True, a, g["detour_b"], g["shared"], g["b_in"]))
        route = pickup + g["rest"] + (0.0 if self.sw.pickup_from_first_origin else between)
        veh.active_at = t + SECONDS_PER_M * route
        veh.node = int(self.d[b]) if g["fofo"] else int(self.d[a])
        veh.p0, veh.picked, veh.leg, veh.p0_pickup_m, veh.idle_route = -1, False, None, 0.0, []

    def _first_wait(self, a: int) -> float:
        for o, _v, t in self.assigned:
            if o == a:
                return t - self.req[a]
        return np.nan

    def _recorded(self, a: int) -> bool:
        return any(r.order == a for r in self.records)

    def _update_record(self, a: int, **changes) -> None:
        for r in self.records:
            if r.order == a:
                for key, value in changes.items():
                    setattr(r, key, value)

    def _deliver_solo(self, vi: int, veh: Vehicle, t: float, vacant_from: float) -> None:
        a = veh.p0
        if self.sw.authors_ledger:
            self.records.append(
                Record(a, vi, veh.assigned_s, self._first_wait(a), veh.p0_pickup_m, ride_m=self.solo[a])
            )
        real_done = veh.assigned_s + SECONDS_PER_M * (self.dist_m(veh.assign_node, self.o[a]) + self.solo[a])
        veh.active_at = vacant_from if self.sw.early_release else max(vacant_from, real_done)
        veh.node = int(self.d[a])
        veh.p0, veh.picked, veh.leg, veh.p0_pickup_m = -1, False, None, 0.0

    def _move_taker(self, vi: int, veh: Vehicle, t: float) -> None:
        if not self.sw.teleport:
            return  # proper movement is advanced by the clock
        a = veh.p0
        if self._timed_out(veh, t):
            travel = self.dist_m(veh.node, self.d[a])
            self._deliver_solo(vi, veh, t, veh.active_at + SECONDS_PER_M * travel)
            return
        target = int(self.o[a]) if not veh.picked else int(self.d[a])
        if veh.node == target:
            if not veh.picked:
                veh.picked = True  # boards this round
                veh.active_at = t
            else:
                self._deliver_solo(vi, veh, t, t)
            return
        path = self.dist.path_nodes(veh.node, target)
        first_link = self.dist_m(path[0], path[1])
        if t - veh.active_at > SECONDS_PER_M * first_link:
            last_link = self.dist_m(path[-2], path[-1])
            if not veh.picked:
                whole = self.dist_m(veh.node, target)
                veh.p0_pickup_m += last_link if (self.sw.authors_ledger and self.strategy == "mb") else whole
                veh.active_at = t
            veh.node = target  # the LAST node of the route: the jump

    def _idle(self, veh: Vehicle, t: float) -> None:
        if not self.sw.idle_jumps:
            return
        if self.sw.teleport and self.strategy == "rtv":
            # The authors' RTV draws a new random target every round and jumps there once the first link's
            # time has passed since the last jump.
            target = int(self.rng.choice(list(self.idle_origins)))
            if target == veh.node:
                veh.reposition_s = t
                return
            path = self.dist.path_nodes(veh.node, target)
            if t > veh.reposition_s + SECONDS_PER_M * self.dist_m(path[0], path[1]):
                veh.reposition_s, veh.node = t, target
            return
        if self.sw.teleport:
            # The authors' other loops (NP, MB, FL-no_delay, FL): a vehicle without a route draws a target and
            # keeps the route's nodes; in every unmatched round, once its first link's time has passed since
            # the last move, it moves to the last node still kept -- the target at once, then back along the
            # route one node per round -- and draws again only when none is left.  Drawing and the first
            # jump can happen in the same round.
            if not veh.idle_route:
                target = int(self.rng.choice(list(self.idle_origins)))
                path = self.dist.path_nodes(veh.node, target)
                veh.idle_route = [int(x) for x in path[1:]]
                veh.idle_first_m = float(self.dist_m(path[0], path[1])) if len(path) > 1 else 0.0
            if not veh.idle_route:
                veh.reposition_s = t  # drew its own node: stays, the round noted
            elif t > veh.reposition_s + SECONDS_PER_M * veh.idle_first_m:
                veh.reposition_s, veh.node = t, veh.idle_route.pop()
            return
        if veh.leg is None or t >= veh.leg.end_s:
            target = int(self.rng.choice(list(self.idle_origins)))
            veh.leg = self._leg(t, [veh.node, target]) if target != veh.node else None

    def _advance_proper(self, t: float) -> None:
        """Proper movement: positions by the clock; a solo passenger is delivered at its real arrival."""
        if self.sw.teleport:
            return
        for vi, veh in enumerate(self.vehicles):
            if veh.leg is None:
                continue
            veh.node = veh.leg.node_at(t)
            if veh.p0 >= 0:
                veh.picked = t >= veh.pickup_s
                if t >= veh.arrive_s:
                    self._deliver_solo(vi, veh, t, veh.arrive_s)
            elif t >= veh.leg.end_s:
                veh.leg = None
