"""Vehicle routes, positions and stops for the batch-round simulator.

Each vehicle has a *plan*: a node sequence with the time it reaches each
node and its odometer there, driven at the constant speed along shortest
paths of the one distance table.  A plan may carry *stops* (pick-ups and
drop-offs at plan nodes).  Vehicles only turn at nodes: a new plan starts at
an *anchor* node of the current plan (the next node, or the pick-up node of
the passenger already assigned, A14), and everything before the anchor is
moved to the vehicle's history unchanged.  Vacant on-duty vehicles cruise at
random (uniformly among outgoing arcs, avoiding U-turns where possible),
extended lazily; off-duty vacant vehicles stand still at their next node.

Positions are derived from plans, never stepped: at time t a vehicle is
``pre = (tt[k] - t)·v`` metres before the plan node ``k`` it reaches next.
History + plan form the trajectory the event log stores and the checker
verifies (consecutive nodes joined by arcs, driven at the set speed).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.network import Distances, RoadNetwork
from rpbench.sim import routes
from rpbench.sim.lookahead import PlanWindows, advance, gather_positions, refill_from_plan

PICKUP, DROPOFF = 0, 1
CRUISE_ARCS = 24  # random-walk arcs added per extension (~11 km on Haikou)
_EPS_S = 1e-9


@dataclass(slots=True)
class Stop:
    index: int  # position in the plan
    kind: int  # PICKUP or DROPOFF
    order: int  # scenario order index


@dataclass(slots=True)
class Plan:
    nodes: np.ndarray
    tt: np.ndarray  # time at each node (s)
    odo: np.ndarray  # odometer at each node (m)
    stops: list[Stop] = field(default_factory=list)
    cruising: bool = False


class DrivenPart(NamedTuple):
    """A plan's driven part, kept in a vehicle's history: the plan's arrays up to (not including) ``end``.

    The arrays are the plan's own (never changed in place: a cruise's extension makes new ones), so
    keeping them costs no copy; the part is cut out when the trajectory is assembled.
    """

    all_nodes: np.ndarray
    all_tt: np.ndarray
    all_odo: np.ndarray
    end: int

    @property
    def nodes(self) -> np.ndarray:
        return self.all_nodes[: self.end]

    @property
    def tt(self) -> np.ndarray:
        return self.all_tt[: self.end]

    @property
    def odo(self) -> np.ndarray:
        return self.all_odo[: self.end]


def _stop_key(stop: Stop) -> tuple[int, int]:
    """A plan's stop order: by plan index, pick-ups before drop-offs at one node."""
    return stop.index, stop.kind


class FleetState:
    """Mutable vehicle state of one simulation run."""

    def __init__(
        self,
        network: RoadNetwork,
        distances: Distances,
        initial_nodes: np.ndarray,
        speed_mps: float,
        rng: np.random.Generator,
    ):
        self.network = network
        self.distances = distances
        self.speed = float(speed_mps)
        self.rng = rng
        n = len(initial_nodes)
        self.n = n
        self.history: list[list[DrivenPart]] = [[] for _ in range(n)]
        self.plans: list[Plan] = [self._still(int(node), 0.0, 0.0) for node in initial_nodes]
        self.onboard: list[list[int]] = [[] for _ in range(n)]
        self.assigned: list[list[int]] = [[] for _ in range(n)]  # assigned, not yet picked up
        self.load = np.zeros(n, dtype=np.int64)  # passengers assigned or on board
        self.paired = np.zeros(n, dtype=bool)  # carries (or will carry) a pooled pair
        self.on_duty = np.zeros(n, dtype=bool)
        self._version = [0] * n  # plain ints: read and bumped a few times a round, element by element
        self._heap: list[tuple[float, int, int]] = []  # (time of next stop, vehicle, version)
        # Cached next plan node per vehicle, valid until the vehicle reaches it.
        self._next_k = np.zeros(n, dtype=np.int64)
        self._next_node = np.asarray(initial_nodes, dtype=np.int64).copy()
        self._next_tt = np.full(n, -np.inf)
        self._next_odo = np.zeros(n)
        self._idle = np.zeros(n, dtype=bool)
        self._windows = PlanWindows(n)  # plan nodes ahead, for vectorised lookups
        self._missed = np.empty(n, dtype=np.int64)  # vehicles whose window could not answer (:func:`advance`)
        # Outgoing arcs as CSR arrays (heads and lengths in out_arcs order) for the compiled route kernels.
        self._offsets = np.ascontiguousarray(network.out_offsets, dtype=np.int64)
        self._heads = np.ascontiguousarray(network.arc_head[network.out_arcs], dtype=np.int64)
        self._lengths = np.ascontiguousarray(network.arc_length_m[network.out_arcs], dtype=np.float64)
        self._pred = distances.pred

    # --------------------------------------------------------------- plans
    def _still(self, node: int, t: float, odo: float) -> Plan:
        return Plan(np.array([node], np.int32), np.array([t]), np.array([odo]))

    def route_through(self, waypoints: list[int]) -> tuple[np.ndarray, list[int]]:
        """Shortest-path node sequence visiting ``waypoints`` (the first is the start node).

        Returns the tail (without the start node) and the tail index (1-based
        plan index) at which each later waypoint is reached.
        """
        points = np.asarray(waypoints, dtype=np.int64)
        reach = np.zeros(max(len(points) - 1, 0), np.int64)
        if len(reach) == 0:
            return np.zeros(0, np.int32), []
        tail = routes.route_through(self._pred, points, reach)
        if reach[0] < 0:
            s = -1 - int(reach[0])
            raise ParameterError(f"no path from node {int(points[s])} to node {int(points[s + 1])}")
        return tail, reach.tolist()

    def position(self, v: int, t: float) -> tuple[int, int, float]:
        """(plan index of the next node, that node, metres before reaching it) at time ``t``."""
        plan = self.plans[v]
        k = int(plan.tt.searchsorted(t - _EPS_S, side="left"))
        if k >= len(plan.nodes):
            if plan.cruising:
                self._extend_cruise(v, t)
                return self.position(v, t)
            k = len(plan.nodes) - 1
            return k, int(plan.nodes[k]), 0.0
        # Before plan node k the vehicle drives the arc into it (for k = 0, the
        # last arc of its history), so the remaining distance follows from time.
        return k, int(plan.nodes[k]), max(0.0, (plan.tt[k] - t) * self.speed)

    def positions(self, vehicles: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorised :meth:`position` for many vehicles (plan index, next node, metres before it).

        Only vehicles that passed their cached next node are looked up again,
        so a round costs O(vehicles that crossed a node) Python work.
        """
        vehicles = np.asarray(vehicles, dtype=np.int64)
        before = t - _EPS_S
        w = self._windows
        n_missed = advance(
            vehicles, before, t, w.arrays,
            self._next_k, self._next_node, self._next_tt, self._next_odo, self._idle, self._missed,
        )  # fmt: skip
        for v in self._missed[:n_missed].tolist():  # past the window: look up the plan, then refill
            plan = self.plans[v]
            k = -1  # :meth:`position`, in the kernel for the common case
            while True:
                k = refill_from_plan(
                    v, k, before, t, plan.nodes, plan.tt, plan.odo, plan.cruising,
                    self._next_k, self._next_node, self._next_tt, self._next_odo, self._idle, w.arrays,
                )  # fmt: skip
                if k >= 0:
                    break
                k = self.position(v, t)[0]  # past the plan's end: cruise extended, or standing
        return gather_positions(vehicles, t, self.speed, self._next_k, self._next_node, self._next_tt, self._idle)

    def positions_found(self, vehicles: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`positions` as the last call found them, without looking for vehicles that moved on.

        Valid, as :meth:`next_odometers`, for vehicles passed to :meth:`positions` at time ``t`` and not
        replanned since.
        """
        vehicles = np.asarray(vehicles, dtype=np.int64)
        return gather_positions(vehicles, t, self.speed, self._next_k, self._next_node, self._next_tt, self._idle)

    def next_odometers(self, vehicles: np.ndarray) -> np.ndarray:
        """Odometer at the plan node each vehicle reaches next, as found by the last :meth:`positions` call.

        Valid for vehicles passed to :meth:`positions` at the current time and not replanned since.
        """
        return self._next_odo[np.asarray(vehicles, dtype=np.int64)]

    def _invalidate(self, v: int) -> None:
        self._next_tt[v] = -np.inf
        self._idle[v] = False
        self._windows.drop(v)

    def replan(
        self,
        v: int,
        anchor: int,
        nodes_tail: np.ndarray,
        stops: list[Stop],
        *,
        cruising: bool = False,
        start_t: float | None = None,
    ) -> None:
        """Keep the current plan up to plan index ``anchor`` and continue with ``nodes_tail``.

        ``stops`` are indexed in the new plan (0 = the anchor node).  With
        ``start_t`` later than the anchor time the vehicle stands still at the
        anchor until then (used when an off-duty vehicle resumes).
        """
        plan = self.plans[v]
        t0 = self._leave(v, plan, anchor, start_t)
        # the new plan (:func:`~rpbench.sim.routes.plan_arrays`) and its window from its first node, in one call
        start = int(plan.nodes[anchor])
        tail = np.asarray(nodes_tail, dtype=np.int32)
        w = self._windows
        nodes, tt, odo, bad = routes.plan_and_window(
            self._offsets, self._heads, self._lengths, start, tail, t0, float(plan.odo[anchor]), self.speed,
            w.arrays, v, cruising,
        )  # fmt: skip
        if bad >= 0:
            before = start if bad == 0 else int(tail[bad - 1])
            raise ValueError(f"no arc from node {before} to node {int(tail[bad])} in a vehicle's plan")
        self._adopt(v, Plan(nodes, tt, odo, sorted(stops, key=_stop_key) if stops else [], cruising))

    def _leave(self, v: int, plan: Plan, anchor: int, start_t: float | None) -> float:
        """Vehicle ``v``'s plan kept up to index ``anchor`` (into its history); the time the new plan starts."""
        if plan.stops and plan.stops[0].index < anchor:
            raise RuntimeError(f"vehicle {v}: replanning past an unserved stop")  # pragma: no cover
        self.history[v].append(DrivenPart(plan.nodes, plan.tt, plan.odo, anchor + 1))
        return float(plan.tt[anchor]) if start_t is None else max(float(plan.tt[anchor]), start_t)

    def _adopt(self, v: int, new: Plan) -> None:
        """``new`` as vehicle ``v``'s plan, its window filled already; its first stop, if any, queued."""
        self.plans[v] = new
        self._next_tt[v] = -np.inf  # stale: found again in the new plan's window
        self._idle[v] = False
        self._version[v] += 1
        if new.stops:
            heapq.heappush(self._heap, (float(new.tt[new.stops[0].index]), v, self._version[v]))

    def replan_through(
        self,
        vehicles: list[int],
        anchors: list[int],
        waypoints: list[list[int]],
        stops_of: Callable[[int, list[int]], list[Stop]],
    ) -> None:
        """:meth:`route_through` and :meth:`replan` for many vehicles (each at most once): vehicle
        ``vehicles[i]`` keeps its plan up to index ``anchors[i]`` and drives on through ``waypoints[i]`` (the
        first being its plan node there), with the stops ``stops_of(i, reach)`` gives (``reach``: the new
        plan's index of each later waypoint).  The routes, plans and windows are found in one compiled call;
        the plans are the same as one :meth:`replan` each would make.
        """
        if not vehicles:
            return
        wp_start = [0]
        for points in waypoints:
            wp_start.append(wp_start[-1] + len(points))
        flat = np.fromiter(itertools.chain.from_iterable(waypoints), np.int64, wp_start[-1])
        plans = [self.plans[v] for v in vehicles]
        t0, odo0 = _anchor_times(plans, anchors)
        reach = np.zeros(wp_start[-1] - len(vehicles), np.int64)
        w = self._windows
        nodes, tt, odo, plan_start, bad, where, why = routes.routed_plans(
            self._pred, self._offsets, self._heads, self._lengths, self.speed, flat, np.asarray(wp_start, np.int64),
            t0, odo0, reach, np.asarray(vehicles, np.int64), w.arrays,
        )  # fmt: skip
        if bad >= 0:
            points = waypoints[bad]
            if why == 1:
                raise ParameterError(f"no path from node {points[where]} to node {points[where + 1]}")
            p0 = int(plan_start[bad])
            before = int(nodes[p0 + where])
            raise ValueError(f"no arc from node {before} to node {int(nodes[p0 + where + 1])} in a vehicle's plan")
        reach_list, starts = reach.tolist(), plan_start.tolist()
        for i, (v, anchor, plan) in enumerate(zip(vehicles, anchors, plans, strict=True)):
            self._leave(v, plan, anchor, None)
            p0, p1 = starts[i], starts[i + 1]
            stops = stops_of(i, reach_list[wp_start[i] - i : wp_start[i + 1] - i - 1])
            ordered = sorted(stops, key=_stop_key) if stops else []
            self._adopt(v, Plan(nodes[p0:p1], tt[p0:p1], odo[p0:p1], ordered, False))

    def send(self, vehicles: np.ndarray, targets: np.ndarray, t: float) -> None:
        """Vacant vehicles ``vehicles`` (distinct) sent from where they are at time ``t`` to ``targets``, each
        cruising on from there: the shortest path, then a random cruise having come along it.  One compiled
        call for all; the plans are those :meth:`route_through` and :meth:`replan` make one by one, each
        cruise drawing its numbers in the order of ``vehicles`` once every position is found."""
        vehicles = np.asarray(vehicles, dtype=np.int64)
        if not len(vehicles):
            return
        anchors, starts, _ = self.positions(vehicles, t)
        listed, at = vehicles.tolist(), anchors.tolist()
        plans = [self.plans[v] for v in listed]
        t0, odo0 = _anchor_times(plans, at)
        u = self.rng.random((len(listed), CRUISE_ARCS))  # row i: :meth:`_random_walk`'s numbers for vehicle i
        w = self._windows
        nodes, tt, odo, plan_start, bad, why = routes.repositioned_plans(
            self._pred, self._offsets, self._heads, self._lengths, self.speed,
            np.asarray(starts, np.int64), np.asarray(targets, np.int64), u, t0, odo0, vehicles, w.arrays,
        )  # fmt: skip
        if bad >= 0:  # pragma: no cover - a network is strongly connected, and paths follow its arcs
            if why == 1:
                raise ParameterError(f"no path from node {int(starts[bad])} to node {int(targets[bad])}")
            raise ValueError(f"vehicle {listed[bad]}: its route left the network's arcs")
        bounds = plan_start.tolist()
        for i, (v, anchor, plan) in enumerate(zip(listed, at, plans, strict=True)):
            self._leave(v, plan, anchor, None)
            p0, p1 = bounds[i], bounds[i + 1]
            self._adopt(v, Plan(nodes[p0:p1], tt[p0:p1], odo[p0:p1], [], True))

    # -------------------------------------------------------------- cruising
    def start_cruise(self, v: int, anchor: int, t: float | None = None) -> None:
        """Random cruising from plan index ``anchor`` (at time ``t`` if later)."""
        plan = self.plans[v]
        node = int(plan.nodes[anchor])
        prev = int(plan.nodes[anchor - 1]) if anchor > 0 else -1
        u = self.rng.random(CRUISE_ARCS)  # :meth:`_random_walk`'s numbers, drawn as it draws them
        t0 = self._leave(v, plan, anchor, t)
        w = self._windows
        nodes, tt, odo, bad = routes.cruise_and_window(
            self._offsets, self._heads, self._lengths, node, prev, u, t0, float(plan.odo[anchor]), self.speed,
            w.arrays, v,
        )  # fmt: skip
        if bad >= 0:  # pragma: no cover - a random walk follows arcs
            raise ValueError(f"vehicle {v}: a cruise left the network's arcs")
        self._adopt(v, Plan(nodes, tt, odo, [], True))

    def park(self, v: int, anchor: int) -> None:
        """Stop at plan index ``anchor`` and stand still (off duty)."""
        self.replan(v, anchor, np.zeros(0, np.int32), [])

    def _extend_cruise(self, v: int, t: float) -> None:
        plan = self.plans[v]
        while plan.tt[-1] < t + 1.0:
            # :meth:`_random_walk` from the plan's end, timed as a replan times its plan, appended: one call
            nodes, tt, odo, bad = routes.extended_cruise(
                self._offsets, self._heads, self._lengths, plan.nodes, plan.tt, plan.odo, self.speed,
                self.rng.random(CRUISE_ARCS),
            )  # fmt: skip
            if bad >= 0:  # pragma: no cover - a random walk follows arcs
                raise ValueError(f"vehicle {v}: a cruise left the network's arcs")
            plan.nodes, plan.tt, plan.odo = nodes, tt, odo
        self._invalidate(v)

    def random_walk_from(self, node: int, prev: int) -> np.ndarray:
        """A random cruise continuing from ``node`` having come from ``prev``."""
        return self._random_walk(node, prev)

    def _random_walk(self, node: int, prev: int) -> np.ndarray:
        """``CRUISE_ARCS`` random arcs from ``node`` (uniformly among outgoing arcs, no U-turn unless at a dead end)."""
        return routes.random_walk(self._offsets, self._heads, node, prev, self.rng.random(CRUISE_ARCS))

    # ---------------------------------------------------------------- stops
    def due_stops(self, t: float):
        """Yield ``(time, vehicle, stop, node, odometer)`` for every stop due by ``t``, in time order.

        The caller handles each stop (and may replan the vehicle) before the
        next one is produced.
        """
        while self._heap and self._heap[0][0] <= t + _EPS_S:
            _, v, version = heapq.heappop(self._heap)
            if version != self._version[v]:
                continue
            plan = self.plans[v]
            stop = plan.stops.pop(0)
            node = int(plan.nodes[stop.index])
            odo = float(plan.odo[stop.index])
            if plan.stops:
                heapq.heappush(self._heap, (float(plan.tt[plan.stops[0].index]), v, self._version[v]))
            yield float(plan.tt[stop.index]), v, stop, node, odo

    # ------------------------------------------------------------ trajectory
    def trajectory(self, v: int, t_end: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The driven node sequence with times and odometer (up to ``t_end``).

        History and plan, chunk after chunk, each chunk's first node dropped where it repeats the node
        the trajectory has reached at that time (the anchor a replan starts from).
        """
        plan = self.plans[v]
        parts = self.history[v]
        nodes = np.concatenate([p.all_nodes[: p.end] for p in parts] + [plan.nodes])
        tt = np.concatenate([p.all_tt[: p.end] for p in parts] + [plan.tt])
        odo = np.concatenate([p.all_odo[: p.end] for p in parts] + [plan.odo])
        starts = np.cumsum([0] + [p.end for p in parts] + [len(plan.nodes)])
        keep = routes.trajectory_keep(nodes, tt, starts, _EPS_S, np.inf if t_end is None else t_end)
        return nodes[keep], tt[keep], odo[keep]

    def trajectories(self, t_end: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every vehicle's :meth:`trajectory` at once: the vehicles' offsets into the concatenated nodes,
        times and odometers (vehicle ``v`` owns entries ``offsets[v]`` to ``offsets[v + 1]``), then those.

        One concatenation and one compiled pass over all vehicles' chunks instead of a few numpy calls per
        vehicle; the entries are the same.
        """
        nodes, tt, odo, lengths, firsts = [], [], [], [0], [0]
        for v in range(self.n):
            for part in self.history[v]:
                end = part.end
                nodes.append(part.all_nodes[:end])
                tt.append(part.all_tt[:end])
                odo.append(part.all_odo[:end])
                lengths.append(end)
            plan = self.plans[v]
            nodes.append(plan.nodes)
            tt.append(plan.tt)
            odo.append(plan.odo)
            lengths.append(len(plan.nodes))
            firsts.append(len(lengths) - 1)
        all_nodes, all_tt, all_odo = np.concatenate(nodes), np.concatenate(tt), np.concatenate(odo)
        keep, counts = routes.fleet_trajectory_keep(
            all_nodes,
            all_tt,
            np.cumsum(np.asarray(lengths, dtype=np.int64)),
            np.asarray(firsts, dtype=np.int64),
            _EPS_S,
            np.inf if t_end is None else t_end,
        )
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        return offsets, all_nodes[keep], all_tt[keep], all_odo[keep]


def _anchor_times(plans: list[Plan], anchors: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The time and odometer at which each plan is left, at its index ``anchors[i]``: where its new plan starts."""
    t0 = np.array([float(plan.tt[a]) for plan, a in zip(plans, anchors, strict=True)])
    odo0 = np.array([float(plan.odo[a]) for plan, a in zip(plans, anchors, strict=True)])
    return t0, odo0
