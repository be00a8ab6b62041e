"""The authors' simulator semantics as a second engine, each mechanism behind a switch.

This is a re-implementation from reading the authors' public code (no code
copied): a batch round every 10 s releases the passengers who requested in
(t - 10 s, t], offers every free vehicle (vacant, or carrying one passenger =
a *taker*) to every waiting passenger, solves one assignment, then moves the
fleet.  What differs from rpbench's own simulator (``rpbench/sim``, which this
module never touches) is listed in :mod:`rpbench.replication.switches`; each
difference is a switch of :class:`Switches`, all on by default.  What each
strategy does differently in the loop is its
:class:`~rpbench.replication.weights.StrategyRules` (``self.rules``).

The engine uses rpbench's building blocks: the network's all-pairs distances
(:class:`~rpbench.network.Distances`), the solver-agnostic
:class:`~rpbench.model.AssignmentModel` solved by any preset, and the
scenario's orders and fleet.  It writes no event log for rpbench's checker:
teleporting vehicles have no trajectory to check; :mod:`rpbench.check.replication`
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
from rpbench.replication import weights
from rpbench.replication.cells import NO_CELL, node_cells
from rpbench.replication.geometry import TakerGeometry
from rpbench.replication.rtv import authors_pair_geometry
from rpbench.replication.rtv import build_round as build_rtv_round
from rpbench.replication.switches import Switches
from rpbench.scenarios.base import Orders, Scenario

STRATEGIES = tuple(weights.RULES)
SECONDS_PER_M = 0.12  # the authors' unit_driving_time (30 km/h)
DT_S = 10.0
SOLO_TIMEOUT_S = 600.0
AUTHORS_PATIENCE_CONST_S = 90.0
RPBENCH_PATIENCE_FLOOR_S = 30.0  # without the authors' weights every strategy floors the patience

#: A batch's matches: vehicle index -> the passengers it takes (one, or two for an RTV trip).
Matches = dict[int, tuple[int, ...]]


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
    passenger: int = -1  # the one passenger of a taker, -1 when vacant
    picked_up: bool = False  # the taker's passenger is on board
    pickup_s: float = np.nan  # proper movement: when the passenger boards
    arrive_s: float = np.nan  # proper movement: when the passenger reaches the destination
    assigned_s: float = 0.0
    assign_node: int = -1
    pickup_m: float = 0.0  # the authors' ledger of the passenger's pick-up
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
class AuthorsRun:
    """A run of the authors' engine: served passengers, pairs, and the KPIs in the authors' definitions."""

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
    assigned: list[tuple[int, int, float]]  # (order, vehicle, t)
    scenario_orders: Orders  # record ``order`` indexes them
    patience_s: np.ndarray  # the patience the engine applied (floored or not)
    solo_m: np.ndarray

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
    origins); ``release_rank`` (one integer per order) orders each batch's new
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
        self.scenario = scenario
        self.strategy = strategy
        self.rules = weights.RULES[strategy]
        self.preset = preset
        self.switches = switches or Switches()
        self.distances = scenario.network.distances()
        self.shortest_m: np.ndarray = self.distances.dist  # all pairs, [from node, to node]
        orders = scenario.orders
        self.origin = orders.origin.astype(np.int64)
        self.destination = orders.destination.astype(np.int64)
        self.request_s = orders.request_s
        self.solo_m = self.shortest_m[self.origin, self.destination]
        floor = self.rules.patience_floor_s if self.switches.authors_weights else RPBENCH_PATIENCE_FLOOR_S
        self.patience_s = np.maximum(orders.patience_s, floor)
        self.fl_params = weights.fl_params(self.switches.authors_ledger)
        self.seeker_saving_m, self.taker_saving_m = self._predictions(predictions)
        self.denominator = int(denominator if denominator is not None else len(orders))
        self.node_cell = node_cells(scenario.network.lon, scenario.network.lat) if self.switches.grid_cells else None
        self.vehicles = [Vehicle(node=int(n)) for n in scenario.fleet.initial_node]
        # The authors draw idle targets from the sampled origins with Python's global random state, last
        # seeded by the fleet placement (random.seed(n - 1) followed by one choice).
        self.idle_origins = (
            np.asarray(reposition_origins) if reposition_origins is not None else np.asarray(pd.unique(self.origin))
        )
        self.rng = random.Random(len(self.vehicles) - 1)
        self.rng.choice(list(self.idle_origins))
        self.release_rank = None if release_rank is None else np.asarray(release_rank, dtype=np.int64)
        if self.release_rank is not None and len(self.release_rank) != len(orders):
            raise ParameterError(f"release_rank has {len(self.release_rank)} entries for {len(orders)} orders")
        self.records: list[Record] = []
        self.pair_saving_m: list[float] = []
        self.shared_m: list[float] = []
        self.assigned: list[tuple[int, int, float]] = []
        self.responded = np.zeros(len(orders), dtype=bool)
        self.rounds_waited = np.zeros(len(orders))  # k_p: batches a passenger has been kept waiting
        self.just_released = np.ones(len(orders), dtype=bool)  # released this batch, never kept waiting yet

    # ------------------------------------------------------------ inputs
    def _predictions(self, predictions: pd.DataFrame | None) -> tuple[np.ndarray, np.ndarray]:
        """The predicted savings as seeker and as taker per order (zeros for a strategy that reads none)."""
        n = len(self.scenario.orders)
        if not self.rules.uses_predictions:
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
        scale = 2.0 if self.fl_params.double_predictions else 1.0
        return scale * seeker, scale * taker

    def dist_m(self, a: int, b: int) -> float:
        """Shortest distance from node ``a`` to node ``b`` (m)."""
        return self.shortest_m[a, b]

    # ------------------------------------------------------------ the loop
    def run(self) -> AuthorsRun:
        t0 = time.perf_counter()
        waiting: list[int] = []
        released = 0
        n = len(self.request_s)
        rounds = 0
        t = DT_S
        rank = self.release_rank
        while t < self.scenario.horizon_s:  # the authors stop at 09:00:00 without a last batch
            rounds += 1
            new_end = int(np.searchsorted(self.request_s, t, side="right"))
            new = [i for i in range(released, new_end) if self.request_s[i] > t - DT_S]
            if rank is not None:
                new.sort(key=lambda i: rank[i])
            released = new_end
            seekers = new + waiting
            for i in new:
                self.just_released[i] = True
            self._advance_proper(t)
            active = [v for v, veh in enumerate(self.vehicles) if t > veh.active_at]
            if self.switches.teleport and self.rules.early_return and (not seekers or not active):
                # The authors return before moving anyone, and keep passengers with a fixed 90 s patience.
                waiting = [
                    i for i in seekers if not self.responded[i] and t - self.request_s[i] < AUTHORS_PATIENCE_CONST_S
                ]
                self._mark_waiting(waiting, t)
                t += DT_S
                continue
            matches: Matches
            if not (seekers and active):
                matches = {}
            elif self.rules.packs_trips:
                matches = self._match_rtv(t, seekers, active)
            else:
                matches = self._match(t, seekers, active)
            self._apply(t, matches, active)
            waiting = [i for i in seekers if not self.responded[i] and t - self.request_s[i] < self.patience_s[i]]
            self._mark_waiting(waiting, t)
            t += DT_S
        return AuthorsRun(
            strategy=self.strategy,
            switches=self.switches,
            records=self.records,
            pair_saving_m=self.pair_saving_m,
            shared_m=self.shared_m,
            denominator=self.denominator,
            n_orders=n,
            n_vehicles=len(self.vehicles),
            rounds=rounds,
            wall_s=time.perf_counter() - t0,
            assigned=self.assigned,
            scenario_orders=self.scenario.orders,
            patience_s=self.patience_s,
            solo_m=self.solo_m,
        )

    def _mark_waiting(self, waiting: list[int], t: float) -> None:
        for i in waiting:
            self.rounds_waited[i] = np.floor((t - self.request_s[i]) / DT_S)
            self.just_released[i] = False

    # ------------------------------------------------------------ matching
    def _taker_geometry(self, veh: Vehicle, b: np.ndarray) -> TakerGeometry[np.ndarray]:
        """Pick-up, in-vehicle distances, saving and detours of taker ``veh`` taking each passenger of ``b``."""
        dist = self.shortest_m
        a = veh.passenger
        oa, da, la = self.origin[a], self.destination[a], self.solo_m[a]
        ob, db, lb = self.origin[b], self.destination[b], self.solo_m[b]
        if self.switches.pickup_from_first_origin:
            pickup = dist[ob, oa]  # the authors' weight: passenger origin -> first origin
            lead = dist[oa, ob]  # the ledger: first origin -> second origin
        else:
            x = veh.node
            if veh.picked_up:
                lead = dist[oa, x] + dist[x, ob]  # the passenger has ridden O_a -> x along its shortest route
                pickup = dist[x, ob]
            else:
                lead = dist[oa, ob]
                pickup = dist[x, oa] + dist[oa, ob]
        f1, f2 = dist[ob, da], dist[da, db]  # first-on-first-off: O_b -> D_a -> D_b
        l1, l2 = lb, dist[db, da]  # first-on-last-off: O_b -> D_b -> D_a
        fofo = (f1 + f2 < l1 + l2) if self.switches.pickup_from_first_origin else (f1 + f2 <= l1 + l2)
        first_ride = np.where(fofo, lead + f1, lead + l1 + l2)
        second_ride = np.where(fofo, f1 + f2, l1)
        shared = np.where(fofo, f1, l1)
        return TakerGeometry(
            pickup_m=pickup,
            lead_m=lead,
            fofo=fofo,
            first_ride_m=first_ride,
            second_ride_m=second_ride,
            shared_m=shared,
            saving_m=la + lb - (first_ride + second_ride - shared),
            first_detour_m=first_ride - la,
            second_detour_m=second_ride - lb,
            rest_m=np.where(fofo, f1 + f2, l1 + l2),
        )

    def _same_cell(self, nodes: np.ndarray, passengers: np.ndarray) -> np.ndarray:
        """Per vehicle node (rows) and passenger (columns): the node lies in the passenger's origin cell (the
        grid_cells switch; all true without it)."""
        if self.node_cell is None:
            return np.ones((len(nodes), len(passengers)), dtype=bool)
        vehicle_cell = self.node_cell[nodes][:, None]
        return (vehicle_cell == self.node_cell[self.origin[passengers]][None, :]) & (vehicle_cell != NO_CELL)

    def _match(self, t: float, seekers: list[int], active: list[int]) -> Matches:
        """One assignment (Eq. (1)): every free vehicle against every waiting passenger, plus keep-waiting."""
        params = self.scenario.params
        rules = self.rules
        passengers = np.asarray(seekers, dtype=np.int64)
        k = self.rounds_waited[passengers]
        fresh = self.just_released[passengers]
        prio = weights.priority(k, fresh, self.fl_params)
        cols_p: list[int] = []
        cols_v: list[int] = []
        vals: list[float] = []
        authors = self.switches.authors_weights
        off = weights.offset(rules, authors)
        col_of = {vi: c for c, vi in enumerate(active)}
        origins = self.origin[passengers]
        # Vacant vehicles, all at once (a vehicles x passengers block).
        vacant = [vi for vi in active if self.vehicles[vi].passenger < 0]
        if vacant:
            nodes = np.asarray([self.vehicles[vi].node for vi in vacant], dtype=np.int64)
            if rules.reversed_vacant_pickup and self.switches.pickup_from_first_origin:
                pk = self.shortest_m[origins[None, :], nodes[:, None]]  # the authors' reversed direction
            else:
                pk = self.shortest_m[nodes[:, None], origins[None, :]]  # vehicle -> origin
            ok = (pk <= params.max_pickup_m) & self._same_cell(nodes, passengers)
            value = weights.vacant_values(
                rules,
                authors,
                pk,
                self.solo_m[passengers][None, :],
                self.taker_saving_m[passengers][None, :],
                prio[None, :],
            )
            rows, cols = np.nonzero(ok)
            cols_p.extend(cols.tolist())
            cols_v.extend(col_of[vacant[r]] for r in rows.tolist())
            vals.extend((value[rows, cols] + off).tolist())
        for vi in active:
            veh = self.vehicles[vi]
            if veh.passenger < 0 or not rules.pools:
                continue
            ok = self._same_cell(np.asarray([veh.node]), passengers)[0]
            g = self._taker_geometry(veh, passengers)
            ok &= (
                (g.pickup_m <= params.max_pickup_m)
                & (g.first_detour_m <= params.max_detour_m)
                & (g.second_detour_m <= params.max_detour_m)
            )
            if rules.pairs_need_saving:
                ok &= g.saving_m >= 0
            v = weights.taker_values(rules, authors, g.saving_m, g.pickup_m, prio)
            idx = np.flatnonzero(ok)
            cols_p.extend(idx.tolist())
            cols_v.extend([col_of[vi]] * len(idx))
            vals.extend((v[idx] + off).tolist())
        wait = weights.wait_values(
            rules, authors, self.seeker_saving_m[passengers], np.where(fresh, 1.0, k), self.fl_params
        )
        cols_p.extend(range(len(passengers)))
        cols_v.extend([-1] * len(passengers))
        vals.extend(wait.tolist())
        model = AssignmentModel(len(passengers), len(active), cols_p, cols_v, quantize(vals), name="authors-round")
        sol = solve(model, self.preset)
        out: Matches = {}
        for c in sol.chosen:
            if model.col_vehicle[c] >= 0:
                out[active[int(model.col_vehicle[c])]] = (int(passengers[model.col_passenger[c]]),)
        return out

    def _timed_out(self, veh: Vehicle, t: float) -> bool:
        """The authors deliver a taker alone 600 s after the request (less its pick-up time)."""
        return self.switches.authors_weights and bool(
            t - self.request_s[veh.passenger] - SECONDS_PER_M * veh.pickup_m > SOLO_TIMEOUT_S
        )

    def one_taker_geometry(self, veh: Vehicle, b: int, *, from_vehicle: bool) -> TakerGeometry[float]:
        """One passenger's pair geometry as floats; ``from_vehicle`` (with the authors' pick-up rule): the
        authors' RTV test measured from the vehicle's node, without the first passenger's ridden distance."""
        if from_vehicle and self.switches.pickup_from_first_origin:
            lead = float(self.dist_m(veh.node, self.origin[b]))
            return authors_pair_geometry(
                self.shortest_m, self.origin, self.destination, self.solo_m, veh.passenger, b, lead, True
            )
        return self._taker_geometry(veh, np.asarray([b])).first()

    def _match_rtv(self, t: float, seekers: list[int], active: list[int]) -> Matches:
        model, decode = build_rtv_round(self, t, seekers, active)
        if model.n_cols == 0:
            return {}
        sol = solve(model, self.preset)
        return {decode[int(c)][0]: decode[int(c)][1] for c in sol.chosen}

    # ------------------------------------------------------------ commit and move
    def _apply(self, t: float, matches: Matches, active: list[int]) -> None:
        for vi in active:
            veh = self.vehicles[vi]
            trip = matches.get(vi, ())
            if len(trip) == 2:
                for r in trip:
                    self.responded[r] = True
                    self.assigned.append((r, vi, t))
                self._dispatch_two(vi, veh, trip, t)
            elif trip:
                b = trip[0]
                self.responded[b] = True
                self.assigned.append((b, vi, t))
                if veh.passenger >= 0:
                    self._dispatch_pair(vi, veh, b, t)
                else:
                    self._take_first(vi, veh, b, t)
                    if self.rules.moves_when_assigned and self.switches.teleport:
                        self._move_when_assigned(vi, veh, t)
            elif veh.passenger >= 0:
                self._move_taker(vi, veh, t)
            else:
                self._idle(veh, t)

    def _take_first(self, vi: int, veh: Vehicle, b: int, t: float) -> None:
        pickup_m = self.dist_m(veh.node, self.origin[b])
        if not self.rules.pools:
            # The authors' NP: jump to the destination, blocked for the real pick-up and ride.
            done = t + SECONDS_PER_M * (pickup_m + self.solo_m[b])
            self.records.append(Record(b, vi, t, t - self.request_s[b], pickup_m, ride_m=self.solo_m[b]))
            veh.node, veh.active_at, veh.leg, veh.idle_route = int(self.destination[b]), done, None, []
            return
        veh.passenger, veh.picked_up, veh.assigned_s, veh.assign_node = b, False, t, veh.node
        veh.pickup_m = 0.0
        veh.idle_route, veh.leg = [], None
        if not self.switches.authors_ledger:
            self.records.append(Record(b, vi, t, t - self.request_s[b], pickup_m, ride_m=self.solo_m[b]))
        if not self.switches.teleport:
            veh.leg = self._leg(t, [veh.node, int(self.origin[b]), int(self.destination[b])])
            veh.pickup_s = t + SECONDS_PER_M * pickup_m
            veh.arrive_s = veh.leg.end_s
            veh.pickup_m = pickup_m
        elif veh.node == int(self.origin[b]):
            # The authors note the vehicle's node as its "origin" when they assign it; standing at the
            # passenger's origin, it counts as having picked the passenger up, its activity time left as it
            # was (no batch spent boarding, no reset to this batch).
            veh.picked_up = True

    def _move_when_assigned(self, vi: int, veh: Vehicle, t: float) -> None:
        """The authors' RTV moves a vehicle in the batch it is assigned, unless it already stood at the
        passenger's origin (:meth:`_take_first` counted that as the pick-up, activity time kept)."""
        if not veh.picked_up:
            self._move_taker(vi, veh, t)

    def _leg(self, t: float, stops: list[int]) -> Leg:
        nodes = [stops[0]]
        for a, b in itertools.pairwise(stops):
            path = self.distances.path_nodes(a, b)
            nodes.extend(int(x) for x in path[1:])
        nodes_arr = np.asarray(nodes, dtype=np.int64)
        step = self.shortest_m[nodes_arr[:-1], nodes_arr[1:]] if len(nodes_arr) > 1 else np.zeros(0)
        metres = np.concatenate([[0.0], np.cumsum(step)])
        return Leg(t, nodes_arr, t + SECONDS_PER_M * metres, metres)

    def _dispatch_pair(self, vi: int, veh: Vehicle, b: int, t: float) -> None:
        a = veh.passenger
        # Geometry as the matching saw it (before the vehicle is moved to O_a).
        g = self._taker_geometry(veh, np.asarray([b])).first()
        if not veh.picked_up:
            # The authors put the vehicle at O_a; its pick-up distance grows by the whole remaining way
            # (which, with the second pick-up measured from O_a, does not delay the pair).  Driving by the
            # clock, the whole pick-up was booked at assignment already.
            if self.switches.teleport:
                veh.pickup_m += float(self.dist_m(veh.node, self.origin[a]))
            veh.picked_up = True
        pk_b = g.lead_m if self.switches.pickup_from_first_origin else g.pickup_m
        self.pair_saving_m.append(g.saving_m)
        self.shared_m.append(g.shared_m)
        wait_a = self._first_wait(a)
        if self.switches.authors_ledger or not self._recorded(a):
            self.records = [r for r in self.records if r.order != a]
            self.records.append(
                Record(
                    a, vi, veh.assigned_s, wait_a, veh.pickup_m, True, b, g.first_detour_m, g.shared_m, g.first_ride_m
                )
            )
        else:
            self._update_record(
                a, pooled=True, partner=b, detour_m=g.first_detour_m, shared_m=g.shared_m, ride_m=g.first_ride_m
            )
        self.records.append(
            Record(b, vi, t, t - self.request_s[b], pk_b, True, a, g.second_detour_m, g.shared_m, g.second_ride_m)
        )
        route_m = pk_b + g.rest_m
        veh.active_at = t + SECONDS_PER_M * route_m
        if self.switches.pickup_from_first_origin:
            veh.node = int(self.destination[b])
        else:
            veh.node = int(self.destination[b]) if g.fofo else int(self.destination[a])
        veh.passenger, veh.picked_up, veh.leg, veh.pickup_m, veh.idle_route = -1, False, None, 0.0, []

    def _dispatch_two(self, vi: int, veh: Vehicle, trip: tuple[int, ...], t: float) -> None:
        """RTV: a vacant vehicle takes two passengers at once; the earlier request is picked up first."""
        a, b = trip if self.request_s[trip[0]] <= self.request_s[trip[1]] else (trip[1], trip[0])
        pickup = float(self.dist_m(veh.node, self.origin[a]))
        between = float(self.dist_m(self.origin[a], self.origin[b]))
        # The authors count the vehicle's pick-up as the first passenger's ride and leave O_a -> O_b out.
        from_first_origin = self.switches.pickup_from_first_origin
        lead = pickup if from_first_origin else between
        g = authors_pair_geometry(
            self.shortest_m, self.origin, self.destination, self.solo_m, a, b, lead, from_first_origin
        )
        self.pair_saving_m.append(g.saving_m)
        self.shared_m.append(g.shared_m)
        self.records.append(
            Record(a, vi, t, t - self.request_s[a], pickup, True, b, g.first_detour_m, g.shared_m, g.first_ride_m)
        )
        self.records.append(
            Record(b, vi, t, t - self.request_s[b], between, True, a, g.second_detour_m, g.shared_m, g.second_ride_m)
        )
        route = pickup + g.rest_m + (0.0 if from_first_origin else between)
        veh.active_at = t + SECONDS_PER_M * route
        veh.node = int(self.destination[b]) if g.fofo else int(self.destination[a])
        veh.passenger, veh.picked_up, veh.leg, veh.pickup_m, veh.idle_route = -1, False, None, 0.0, []

    def _first_wait(self, a: int) -> float:
        for order, _vehicle, t in self.assigned:
            if order == a:
                return t - self.request_s[a]
        return np.nan

    def _recorded(self, a: int) -> bool:
        return any(r.order == a for r in self.records)

    def _update_record(self, a: int, **changes: object) -> None:
        for r in self.records:
            if r.order == a:
                for key, value in changes.items():
                    setattr(r, key, value)

    def _deliver_solo(self, vi: int, veh: Vehicle, t: float, vacant_from: float) -> None:
        a = veh.passenger
        if self.switches.authors_ledger:
            self.records.append(Record(a, vi, veh.assigned_s, self._first_wait(a), veh.pickup_m, ride_m=self.solo_m[a]))
        real_done = veh.assigned_s + SECONDS_PER_M * (self.dist_m(veh.assign_node, self.origin[a]) + self.solo_m[a])
        veh.active_at = vacant_from if self.switches.early_release else max(vacant_from, real_done)
        veh.node = int(self.destination[a])
        veh.passenger, veh.picked_up, veh.leg, veh.pickup_m = -1, False, None, 0.0

    def _move_taker(self, vi: int, veh: Vehicle, t: float) -> None:
        if not self.switches.teleport:
            return  # proper movement is advanced by the clock
        a = veh.passenger
        if self._timed_out(veh, t):
            travel = self.dist_m(veh.node, self.destination[a])
            self._deliver_solo(vi, veh, t, veh.active_at + SECONDS_PER_M * travel)
            return
        target = int(self.origin[a]) if not veh.picked_up else int(self.destination[a])
        if veh.node == target:
            if not veh.picked_up:
                veh.picked_up = True  # boards this batch
                veh.active_at = t
            else:
                self._deliver_solo(vi, veh, t, t)
            return
        path = self.distances.path_nodes(veh.node, target)
        first_link = self.dist_m(path[0], path[1])
        if t - veh.active_at > SECONDS_PER_M * first_link:
            last_link = self.dist_m(path[-2], path[-1])
            if not veh.picked_up:
                whole = self.dist_m(veh.node, target)
                veh.pickup_m += last_link if (self.switches.authors_ledger and self.rules.ledger_last_link) else whole
                veh.active_at = t
            veh.node = target  # the LAST node of the route: the jump

    def _idle(self, veh: Vehicle, t: float) -> None:
        if not self.switches.idle_jumps:
            return
        if self.switches.teleport and self.rules.idle_redraw_every_batch:
            # The authors' RTV draws a new random target every batch and jumps there once the first link's
            # time has passed since the last jump.
            target = int(self.rng.choice(list(self.idle_origins)))
            if target == veh.node:
                veh.reposition_s = t
                return
            path = self.distances.path_nodes(veh.node, target)
            if t > veh.reposition_s + SECONDS_PER_M * self.dist_m(path[0], path[1]):
                veh.reposition_s, veh.node = t, target
            return
        if self.switches.teleport:
            # The authors' other loops (NP, MB, FL-no_delay, FL): a vehicle without a route draws a target and
            # keeps the route's nodes; in every unmatched batch, once its first link's time has passed since
            # the last move, it moves to the last node still kept -- the target at once, then back along the
            # route one node per batch -- and draws again only when none is left.  Drawing and the first
            # jump can happen in the same batch.
            if not veh.idle_route:
                target = int(self.rng.choice(list(self.idle_origins)))
                path = self.distances.path_nodes(veh.node, target)
                veh.idle_route = [int(x) for x in path[1:]]
                veh.idle_first_m = float(self.dist_m(path[0], path[1])) if len(path) > 1 else 0.0
            if not veh.idle_route:
                veh.reposition_s = t  # drew its own node: stays, the batch noted
            elif t > veh.reposition_s + SECONDS_PER_M * veh.idle_first_m:
                veh.reposition_s, veh.node = t, veh.idle_route.pop()
            return
        if veh.leg is None or t >= veh.leg.end_s:
            target = int(self.rng.choice(list(self.idle_origins)))
            veh.leg = self._leg(t, [veh.node, target]) if target != veh.node else None

    def _advance_proper(self, t: float) -> None:
        """Proper movement: positions by the clock; a solo passenger is delivered at its real arrival."""
        if self.switches.teleport:
            return
        for vi, veh in enumerate(self.vehicles):
            if veh.leg is None:
                continue
            veh.node = veh.leg.node_at(t)
            if veh.passenger >= 0:
                veh.picked_up = t >= veh.pickup_s
                if t >= veh.arrive_s:
                    self._deliver_solo(vi, veh, t, veh.arrive_s)
            elif t >= veh.leg.end_s:
                veh.leg = None
