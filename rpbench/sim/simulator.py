"""The batch-round simulator (paper §2.1 and §4.1).

Before the first round the strategy's ``prepare`` gets what is known before
the day: the scenario's :class:`~rpbench.scenarios.base.OnlineView`, without
its orders (the whole scenario only for a strategy that declares itself
clairvoyant, whose run is then marked so).  Every Δt seconds, at rounds
t = 0, Δt, 2Δt, ...:

1. process the pick-ups and drop-offs vehicles reached by t (a vehicle whose
   last passenger leaves becomes vacant and cruises at random);
2. reveal the orders requested by t; cancel waiting passengers whose
   patience K_p ran out (``t - t_request > K_p``; never assigned);
3. build the round state (waiting passengers with rounds waited k_p; vacant
   vehicles V0; partially occupied vehicles V1 — exactly one unpaired
   passenger on board *or assigned*, including vehicles still driving to that
   first passenger; full vehicles excluded);
4. ask the strategy for a model, solve it with the preset's backend, resolve
   ties among optima solver-independently (:mod:`rpbench.sim.ties`) and commit
   the decisions (assignments are final), then move the vacant vehicles the
   strategy repositions; in a round where nobody waits, only the latter
   (:meth:`~rpbench.strategies.base.Strategy.idle_moves`);
5. record events and per-round solver statistics.

Vehicles move along shortest paths at the set speed between rounds
(:mod:`rpbench.sim.fleet`).  Capacity is one pooled pair.  The run ends when
every order has been revealed and resolved; vehicles then finish their
passengers.
"""

from __future__ import annotations

import gc
import math
import os
import re
import stat
import tempfile
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from operator import itemgetter
from pathlib import Path
from typing import TypeVar

import numpy as np
import pandas as pd

from rpbench.backends import Preset, solve
from rpbench.exceptions import ModelError, SolverError
from rpbench.files.paths import cache_dir
from rpbench.model import Solution, Status
from rpbench.model import kernels as model_kernels
from rpbench.model.instances import save_instance
from rpbench.scenarios.base import Scenario
from rpbench.sim import gather, lookahead, routes, ties
from rpbench.sim.fleet import DROPOFF, PICKUP, FleetState, Stop
from rpbench.sim.ties import canonicalize
from rpbench.strategies import base as strategy_base
from rpbench.strategies import candidates
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy, received, received_moves

T = TypeVar("T")

#: ``capture(round, t, round_model, solution)``: a hook that sees every solved round.
Capture = Callable[[int, float, RoundModel, Solution], None]

# passenger states
PENDING, WAITING, ASSIGNED, ONBOARD, DONE, CANCELLED = range(6)
# column kinds as plain ints (compared once per committed column)
_WAIT, _VACANT, _JOIN, _TRIP2 = int(Kind.WAIT), int(Kind.VACANT), int(Kind.JOIN), int(Kind.TRIP2)
EVENT_COLUMNS = ["t_s", "event", "order", "vehicle", "node", "kind", "utility_m", "pickup_plan_m", "partner", "fofo"]
EVENT_DTYPES = {
    "t_s": "float64",
    "event": "object",
    "order": "int64",
    "vehicle": "int64",
    "node": "int64",
    "kind": "object",
    "utility_m": "float64",
    "pickup_plan_m": "float64",
    "partner": "int64",
    "fofo": "bool",
}
ROUND_COLUMNS = [
    "round",
    "t_s",
    "waiting",
    "v0",
    "v1",
    "rows",
    "cols",
    "nonzeros",
    "strategy_build_s",
    "solver_build_s",
    "solve_s",
    "extract_s",
    "status",
    "objective_m",
    "gap",
    "assigned",
    "tie_moves",
]


@dataclass
class SimResult:
    """What one simulation run produced (everything the results folder stores)."""

    strategy: str
    events: pd.DataFrame
    rounds: pd.DataFrame
    trajectories: dict[str, np.ndarray]  # vehicle_offsets, node, t_s, odo_m
    wall_s: float  # the round loop: the strategy's decisions, the solves and the simulation
    end_s: float
    #: The strategy's one-off :meth:`~rpbench.strategies.base.Strategy.prepare` (loading or building its
    #: predictions and their caches), timed apart so that a first run's cache builds are not charged to
    #: the strategy's own time.
    prepare_s: float = 0.0
    #: What the run's decisions depend on besides the scenario (:meth:`Strategy.artefacts`): name ->
    #: (digest, folder), copied into the results folder.
    artefacts: dict[str, tuple[str, Path]] = field(default_factory=dict)
    #: The strategy read the future: its ``prepare`` got the whole scenario (:meth:`Strategy.clairvoyant_on`).
    clairvoyant: bool = False


#: Where a failed round's model is dumped: a private folder of the cache, not the shared /tmp.
FAILED_ROUNDS = "failed-rounds"


def _new_dump_file(stem: str) -> Path:
    """A new, empty file of our own in ``<cache>/failed-rounds/`` to dump a failed round's model into.

    The name is unpredictable and created with O_EXCL (``mkstemp``), so a link planted under a
    guessable name is never followed and concurrent runs never clobber each other's dumps; the
    folder is ours and private (0700), so nobody can swap the file for a link before it is written.
    """
    folder = cache_dir() / FAILED_ROUNDS
    folder.mkdir(mode=0o700, exist_ok=True)
    st = os.lstat(folder)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid():
        raise OSError(f"{folder} is a link or not our own folder: not dumping into it")
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", stem)  # plug-in names hold ':' (mypkg.rules:Greedy)
    fd, name = tempfile.mkstemp(prefix=f"{safe}-", suffix=".npz", dir=folder)
    os.close(fd)
    return Path(name)


@contextmanager
def _older_objects_frozen():
    """The objects made before the run kept out of the garbage collector's full passes (``gc.freeze``).

    A round allocates little, but a full collection its allocations trigger scans every object the
    process holds (10^5 and more: the scenario, the tables, imported modules), about 0.1 s on a peak
    hour's first run; none of them is the run's garbage.  They are handed back when the run ends; a
    caller that froze objects itself keeps the collector as it set it.
    """
    if gc.get_freeze_count():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _load_solver_libraries(preset: Preset) -> None:
    """The preset's backend loads its solver library now (:meth:`~rpbench.backends.base.Backend.load`):
    ``import rpbench`` loads no solver, and the first solve would otherwise import it in the first round.
    An unknown or broken preset is left for the solve to report."""
    try:
        load = getattr(preset.adapter(), "load", None)
        if load is not None:
            load()
    except Exception:  # reported by the solve, with the backend's own message
        return


class Simulator:
    """One run of one strategy on one scenario with one solver backend."""

    def __init__(
        self,
        scenario: Scenario,
        strategy: Strategy,
        preset: Preset,
        *,
        canonical_ties: bool = True,
        progress=None,
        capture: Capture | None = None,
        strict: bool = False,
    ):
        """``capture(round, t, round_model, solution)``, if given, sees every solved round (snapshots).

        ``strict``: a round the solver stops before proving its optimum (time limit, gap) is an error
        instead of a ``time_limit``/``feasible`` row in the round statistics (``--strict``).
        """
        self.strict = strict
        self.scenario = scenario
        self.strategy = strategy
        self.preset = preset
        self.canonical_ties = canonical_ties
        self.progress = progress
        self.capture = capture
        self.params = scenario.params
        self.distances = scenario.network.distances()
        self.dist = self.distances.dist
        o = scenario.orders
        self.n_orders = len(o)
        self.origin = o.origin.astype(np.int64)
        self.destination = o.destination.astype(np.int64)
        self.request = np.ascontiguousarray(o.request_s, dtype=np.float64)
        self.patience = o.patience_s
        self.solo = self.dist[self.origin, self.destination] if self.n_orders else np.zeros(0)
        self._origin_list: list[int] = self.origin.tolist()  # waypoints of the routes a commit plans
        self._destination_list: list[int] = self.destination.tolist()
        self._request_list: list[float] = self.request.tolist()  # read one by one each round
        self._patience_list: list[float] = np.asarray(self.patience, dtype=np.float64).tolist()
        self.state = np.full(self.n_orders, PENDING, dtype=np.int8)
        self.vehicle_of = np.full(self.n_orders, -1, dtype=np.int64)
        self.pickup_odo = np.full(self.n_orders, np.nan)
        self.rider = np.full(len(scenario.fleet.initial_node), -1, dtype=np.int64)  # last vacant assignment
        rng = np.random.default_rng(np.random.SeedSequence([scenario.seed, 20170501]))
        self.fleet = FleetState(
            scenario.network, self.distances, scenario.fleet.initial_node, self.params.speed_mps, rng
        )
        self.events: list[tuple] = []
        self.rounds: list[tuple] = []
        self.waiting: list[int] = []
        self._n_on = -1  # vehicles on duty in the previous round (-1: none looked at yet)
        # the compiled kernels' one-off load, before the first round rather than in it
        routes.load_route_kernels()
        lookahead.load_lookahead_kernels()
        gather.load_gather_kernels()
        ties.load_tie_kernels()
        model_kernels.load_model_kernels()
        candidates.load_candidate_kernels()
        strategy_base.load_state_kernels()
        _load_solver_libraries(preset)

    # ------------------------------------------------------------------ run
    def run(self) -> SimResult:
        """Every round of the scenario, then the event log, round statistics and trajectories; the strategy's
        :meth:`~rpbench.strategies.base.Strategy.finish` runs however the loop ends."""
        try:
            return self._run()
        finally:
            self.strategy.finish()

    def _run(self) -> SimResult:
        t_prepare = time.perf_counter()
        # An online strategy knows the day's orders only as rounds reveal them; only one that says it reads
        # the future gets them all up front (and its run is marked so).
        clairvoyant = bool(self.strategy.clairvoyant_on(self.scenario))
        self.strategy.prepare(self.scenario if clairvoyant else self.scenario.online_view(self._strategy_text()))
        candidates.prepare_tables(self.dist, self.params)  # the option search's table, with the run's preparation
        with _older_objects_frozen():
            return self._loop(t_prepare, clairvoyant)

    def _loop(self, t_prepare: float, clairvoyant: bool) -> SimResult:
        t0 = time.perf_counter()
        prepare_s = t0 - t_prepare
        dt = self.params.dt_s
        # Rounds where nobody waits build no state, unless the strategy moves idle vehicles in them.
        idle_moves = type(self.strategy).idle_moves is not Strategy.idle_moves
        next_order = 0
        k = 0
        t = 0.0
        last_request = float(self.request[-1]) if self.n_orders else 0.0
        requests = self._request_list
        while True:
            t = k * dt
            self._process_stops(t)
            self._update_duty(t)
            while next_order < self.n_orders and requests[next_order] <= t:
                self.state[next_order] = WAITING
                self.waiting.append(next_order)
                self._event(requests[next_order], "request", next_order, -1, self._origin_list[next_order])
                next_order += 1
            self._expire(t)
            if self.waiting:
                self._round(k, t)
            elif idle_moves:
                self._idle_round(k, t)
            if self.progress is not None:
                self.progress.update(min(t, self.scenario.horizon_s) - self.progress.n)
            if next_order >= self.n_orders and not self.waiting and t >= last_request:
                break
            k += 1
        self._process_stops(math.inf)
        end = max(t, max(map(itemgetter(0), self.events), default=t))
        return SimResult(
            strategy=self.strategy.name,
            events=self._event_table(),
            rounds=pd.DataFrame(self.rounds, columns=ROUND_COLUMNS),
            trajectories=self._trajectories(end),
            wall_s=time.perf_counter() - t0,
            end_s=end,
            prepare_s=prepare_s,
            artefacts=self.strategy.artefacts(),
            clairvoyant=clairvoyant,
        )

    # ------------------------------------------------------------ per round
    def _round(self, k: int, t: float) -> None:
        t_build = time.perf_counter()
        state = self._round_state(t)
        built = self._checked(k, t, lambda: self.strategy.build(state))  # a model it failed to construct
        build_s = time.perf_counter() - t_build
        # Checked here, once built (a strategy may change its arrays after constructing them), and
        # copied into arrays it can no longer change: the solver and the commit see what was checked.
        rm = self._checked(k, t, lambda: received(built, state, self.strategy.structure))
        model = rm.model
        if model.n_cols == 0:  # nothing to decide: the strategy may still move idle vehicles
            self._move(k, t, state, rm, np.zeros(0, np.int64))
            return
        try:
            solution = solve(model, self.preset)  # verified there: a valid, feasible answer
        except SolverError as exc:
            raise self._round_failure(k, t, model, str(exc)) from None
        if solution.status is Status.INFEASIBLE:
            raise self._round_failure(k, t, model, f"returned {solution.status.value}: {solution.message}")
        if self.strict and solution.status is not Status.OPTIMAL:
            # Fail at the first unproven round, not after hours of simulating on top of it.
            raise self._round_failure(
                k,
                t,
                model,
                f"stopped with status {solution.status.value}, not proven "
                "optimal (--strict); raise the preset's time_limit_s or "
                "choose a faster exact preset",
            )
        if self.capture is not None:
            self.capture(k, t, rm, solution)
        tie_moves = 0
        if self.canonical_ties:
            solution, tie_moves = canonicalize(model, solution)
        assigned = self._commit(rm, solution.chosen, t)
        self._move(k, t, state, rm, solution.chosen)
        size = model.size
        self.rounds.append(
            (
                k,
                t,
                state.n_passengers,
                state.n_v0,
                state.n_v1,
                size["rows"],
                size["cols"],
                size["nonzeros"],
                build_s,
                solution.build_s,
                solution.solve_s,
                solution.extract_s,
                solution.status.value,
                solution.objective * model.unit_m,
                solution.gap,
                assigned,
                tie_moves,
            )
        )

    def _move(self, k: int, t: float, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> None:
        """The strategy's repositioning of vacant vehicles after the round's decisions (``chosen`` columns)."""
        moves = self.strategy.reposition(state, rm, chosen)
        used = rm.vehicle[chosen]
        vehicles, targets = self._checked(k, t, lambda: received_moves(moves, state, used, len(self.dist)))
        self._reposition(vehicles, targets, t)

    def _idle_round(self, k: int, t: float) -> None:
        """A round where nobody waits: no model, only the strategy's moves of idle vacant vehicles."""
        state = self._round_state(t)
        moves = self._checked(k, t, lambda: self.strategy.idle_moves(state))
        none = np.zeros(0, np.int64)
        vehicles, targets = self._checked(k, t, lambda: received_moves(moves, state, none, len(self.dist)))
        self._reposition(vehicles, targets, t)

    def _strategy_text(self) -> str:
        """The strategy as error lines name it: its run name and class."""
        cls = type(self.strategy)
        return f"strategy {self.strategy.name!r} ({cls.__module__}.{cls.__qualname__})"

    def _checked(self, k: int, t: float, check: Callable[[], T]) -> T:
        """``check()``, its :class:`ModelError` naming the strategy (run name and class) and the round."""
        try:
            return check()
        except ModelError as exc:
            raise ModelError(f"{self._strategy_text()} round {k} (t={t:g} s): {exc}") from None

    def _round_failure(self, k: int, t: float, model, what: str) -> SolverError:
        """A solver failure naming the strategy and round, with the round's model saved for `rpbench bench`."""

        where = f"{self.strategy.name} round {k} (t={t:g} s): solver preset {self.preset.name!r}: {what}"
        meta = {
            "scenario": self.scenario.name,
            "seed": self.scenario.seed,
            "strategy": self.strategy.name,
            "round": k,
            "t_s": t,
            "error": what,
        }
        try:
            path = _new_dump_file(f"{self.strategy.name}-round{k:05d}")
        except OSError:
            return SolverError(where)
        try:
            save_instance(path, model, meta)
        except OSError:
            path.unlink(missing_ok=True)
            return SolverError(where)
        return SolverError(f"{where}; the round's model is saved as {path} (reproduce: rpbench bench {path})")

    def _round_state(self, t: float) -> RoundState:
        fl = self.fleet
        p = np.asarray(self.waiting, dtype=np.int64)
        v0, v1 = gather.fleet_split(fl.load, fl.paired, fl.on_duty)
        _, v0_node, v0_pre = fl.positions(v0, t)
        # A V1 vehicle's one passenger is the one its vacant assignment gave it (a join or a
        # trip pairs the vehicle), so one array lookup replaces a scan of its passenger lists.
        v1_order = self.rider[v1]
        if len(v1):
            _, node_next, pre_next = fl.positions(v1, t)
            odo_next = fl.next_odometers(v1)
        else:
            node_next, pre_next, odo_next = v1, np.zeros(0), np.zeros(0)
        # not yet picked up: h = o_A, δ = 0, pre = 0 (A14)
        v1_node, v1_delta, v1_pre, v1_onboard, v1_origin, v1_destination, v1_solo = gather.riders(
            v1_order, self.state, ONBOARD, self.origin, self.destination, self.solo, self.pickup_odo,
            node_next, pre_next, odo_next,
        )  # fmt: skip
        origin, destination, solo, request, waited = gather.passengers(
            p, self.origin, self.destination, self.solo, self.request, t, self.params.dt_s
        )
        return RoundState(
            t_s=t,
            params=self.params,
            dist=self.dist,
            p_order=p,
            p_origin=origin,
            p_destination=destination,
            p_solo_m=solo,
            p_request_s=request,
            p_rounds_waited=waited,
            v0_vehicle=v0,
            v0_node=v0_node,
            v0_pre_m=v0_pre,
            v1_vehicle=v1,
            v1_node=v1_node,
            v1_delta_m=v1_delta,
            v1_pre_m=v1_pre,
            v1_order=v1_order,
            v1_origin=v1_origin,
            v1_destination=v1_destination,
            v1_solo_m=v1_solo,
            v1_onboard=v1_onboard,
        )

    # --------------------------------------------------------------- commit
    def _commit(self, rm: RoundModel, chosen: np.ndarray, t: float) -> int:
        fl = self.fleet
        origin, destination = self._origin_list, self._destination_list
        assigned: list[int] = []
        # Every chosen vehicle's position at once: each vehicle is chosen once, and replanning one
        # leaves the others' positions as they were.  The round state found them at t (the chosen
        # vehicles are the round's V0 and V1, which received() checks), and nothing moved since.
        # The chosen columns' fields are read as Python values once, not element by element.
        moving = chosen[rm.kind[chosen] != _WAIT]
        vehicles = rm.vehicle[moving]
        ks, hs, _ = fl.positions_found(vehicles, t)
        columns = zip(
            rm.kind[moving].tolist(),
            vehicles.tolist(),
            rm.first[moving].tolist(),
            rm.second[moving].tolist(),
            rm.fofo[moving].tolist(),
            rm.utility_m[moving].tolist(),
            rm.pickup_m[moving].tolist(),
            ks.tolist(),
            hs.tolist(),
            strict=True,
        )
        # First every chosen column's route (its anchor, waypoints and how its stops follow from them), then
        # the vehicles replanned in one call, then the assignments in column order.
        vehicle_ids: list[int] = []
        anchors: list[int] = []
        waypoints: list[list[int]] = []
        stop_rules: list[tuple] = []
        assigns: list[tuple] = []
        for kind, v, a, b, fofo, utility, pickup, k, h in columns:
            if kind == _VACANT:
                anchor, points = k, [h, origin[a], destination[a]]
                stop_rules.append((_VACANT, a, 0, 0, 0))
                assigns.append((v, a, "vacant", utility, pickup, -1, fofo, False))
            elif kind == _JOIN:
                onboard = fl.onboard[v]
                first = onboard[0] if onboard else fl.assigned[v][0]
                drops = self._drop_order(first, a, fofo)
                if onboard:
                    anchor, points = k, [h, origin[a], destination[drops[0]], destination[drops[1]]]
                else:  # divert after picking up the first passenger at o_A (A14)
                    plan = fl.plans[v]
                    anchor = next(s.index for s in plan.stops if s.kind == PICKUP and s.order == first)
                    points = [int(plan.nodes[anchor]), origin[a], destination[drops[0]], destination[drops[1]]]
                stop_rules.append((_JOIN, a, first if not onboard else -1, drops[0], drops[1]))
                assigns.append((v, a, "join", utility, pickup, first, fofo, True))
            elif kind == _TRIP2:
                drops = self._drop_order(a, b, fofo)
                anchor, points = k, [h, origin[a], origin[b], destination[drops[0]], destination[drops[1]]]
                stop_rules.append((_TRIP2, a, b, drops[0], drops[1]))
                assigns.append((v, a, "trip2", utility, pickup, b, fofo, True))
                assigns.append((v, b, "trip2", utility, pickup, a, fofo, True))
            else:
                continue
            vehicle_ids.append(v)
            anchors.append(anchor)
            waypoints.append(points)

        def stops_of(i: int, reach: list[int]) -> list[Stop]:
            rule, a, x, drop0, drop1 = stop_rules[i]
            if rule == _VACANT:
                return [Stop(reach[0], PICKUP, a), Stop(reach[1], DROPOFF, a)]
            if rule == _JOIN:  # x: the first passenger when still to be picked up at the anchor, else -1
                stops = [Stop(reach[0], PICKUP, a)] if x < 0 else [Stop(0, PICKUP, x), Stop(reach[0], PICKUP, a)]
                return [*stops, Stop(reach[1], DROPOFF, drop0), Stop(reach[2], DROPOFF, drop1)]
            return [
                Stop(reach[0], PICKUP, a),
                Stop(reach[1], PICKUP, x),
                Stop(reach[2], DROPOFF, drop0),
                Stop(reach[3], DROPOFF, drop1),
            ]

        fl.replan_through(vehicle_ids, anchors, waypoints, stops_of)
        for v, order, kind_name, utility, pickup, partner, fofo, paired in assigns:
            if paired:
                fl.paired[v] = True
            else:
                self.rider[v] = order
            self._assign(order, v, t, kind_name, utility, pickup, partner, fofo)
            assigned.append(order)
        if assigned:
            taken = set(assigned)
            left = [o for o in self.waiting if o not in taken]
            if len(self.waiting) - len(left) != len(assigned):  # pragma: no cover - received() rules it out
                raise RuntimeError(f"round at t={t:g} s assigned an order twice or one that was not waiting")
            self.waiting = left
        return len(assigned)

    def _reposition(self, vehicles: np.ndarray, targets: np.ndarray, t: float) -> None:
        """Send vacant vehicles to ``targets``; they stay vacant and cruise on from there."""
        self.fleet.send(vehicles, targets, t)
        for v, node in zip(vehicles.tolist(), targets.tolist(), strict=True):
            self._event(t, "reposition", -1, v, node)

    @staticmethod
    def _drop_order(a: int, b: int, a_first: bool) -> list[int]:
        """The two orders in drop-off sequence (FOFO: the first passenger is dropped first)."""
        return [a, b] if a_first else [b, a]

    def _assign(
        self, order: int, v: int, t: float, kind: str, utility: float, pickup: float, partner: int, fofo: bool
    ) -> None:
        """``order`` assigned to vehicle ``v`` (the caller takes it off the waiting list)."""
        self.state[order] = ASSIGNED
        self.vehicle_of[order] = v
        self.fleet.assigned[v].append(order)
        self.fleet.load[v] += 1
        self._event(t, "assign", order, v, -1, kind, utility, pickup, partner, fofo)

    # ---------------------------------------------------------------- stops
    def _process_stops(self, t: float) -> None:
        fl = self.fleet
        for when, v, stop, node, odo in fl.due_stops(t):
            o = stop.order
            if stop.kind == PICKUP:
                fl.assigned[v].remove(o)
                fl.onboard[v].append(o)
                self.state[o] = ONBOARD
                self.pickup_odo[o] = odo
                self._event(when, "pickup", o, v, node)
            else:
                fl.onboard[v].remove(o)
                fl.load[v] -= 1
                self.state[o] = DONE
                self._event(when, "dropoff", o, v, node)
                if not fl.onboard[v] and not fl.assigned[v]:
                    fl.paired[v] = False
                    if fl.on_duty[v]:
                        fl.start_cruise(v, stop.index)
                    else:
                        fl.park(v, stop.index)

    def _update_duty(self, t: float) -> None:
        fl = self.fleet
        n_on = self.scenario.fleet.on_duty(t)
        if n_on == self._n_on:
            return  # the same vehicles on duty as in the previous round
        self._n_on = n_on
        want = np.arange(fl.n) < n_on
        for changed in np.flatnonzero(want != fl.on_duty):
            v = int(changed)
            fl.on_duty[v] = want[v]
            if fl.onboard[v] or fl.assigned[v]:
                continue  # busy vehicles finish their passengers first
            plan = fl.plans[v]
            if want[v]:
                fl.start_cruise(v, len(plan.nodes) - 1 if not plan.cruising else fl.position(v, t)[0], t)
            else:
                fl.park(v, fl.position(v, t)[0])

    def _expire(self, t: float) -> None:
        keep = []
        request, patience = self._request_list, self._patience_list  # the same doubles, read as Python floats
        for o in self.waiting:
            if t - request[o] > patience[o] + 1e-9:
                self.state[o] = CANCELLED
                self._event(request[o] + patience[o], "cancel", o, -1, self._origin_list[o])
            else:
                keep.append(o)
        self.waiting = keep

    # -------------------------------------------------------------- records
    def _event(
        self, t, event, order, vehicle, node, kind="", utility=np.nan, pickup=np.nan, partner=-1, fofo=False
    ) -> None:
        self.events.append(
            (float(t), event, int(order), int(vehicle), int(node), kind, utility, pickup, int(partner), bool(fofo))
        )

    def _event_table(self) -> pd.DataFrame:
        """The event log as a table sorted by time, order and event name (stable: ties keep their order)."""
        if not self.events:
            return pd.DataFrame(self.events, columns=EVENT_COLUMNS).astype(EVENT_DTYPES)
        # column by column, sorted in numpy: a frame built from the rows and sorted by pandas took twice as long
        arrays = {
            name: np.array(column, dtype=object if EVENT_DTYPES[name] == "object" else EVENT_DTYPES[name])
            for name, column in zip(EVENT_COLUMNS, zip(*self.events, strict=True), strict=True)
        }
        # each event name's rank among the few names present, in sorted order (as np.unique ranks them)
        names = [e[1] for e in self.events]
        rank = {name: i for i, name in enumerate(sorted(set(names)))}
        event_rank = np.fromiter(map(rank.__getitem__, names), np.int64, len(names))
        order = np.lexsort((event_rank, arrays["order"], arrays["t_s"]))
        return pd.DataFrame({name: a[order] for name, a in arrays.items()}).astype(EVENT_DTYPES)

    def _trajectories(self, end: float) -> dict[str, np.ndarray]:
        offsets, nodes, tt, odo = self.fleet.trajectories(end)
        return {"vehicle_offsets": offsets, "node": nodes.astype(np.int32), "t_s": tt, "odo_m": odo}
