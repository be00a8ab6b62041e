"""Hindsight: a clairvoyant dispatcher, the best offline schedule rpbench finds (a lower bound on OPT).

It knows every order of the day (time, origin, destination, patience) before the first round and
plans pairs with that knowledge, but every decision is an ordinary round column (or repositioning
move) that the simulator commits under its own rules: R̄, D̄, patience, a JOIN only into a vehicle
with one unpaired passenger, assignments final.  Its run is checked by ``rpbench check`` like every
run, so its saving is the saving of a feasible schedule: ``OPT >= saving``, and ``U >= OPT``
(docs/bound.md, "Hindsight").

**The plan, re-made every ``replan_s`` (30 s).**  The open orders are those waiting, those not yet requested (up to
``horizon_s`` ahead) and the passengers A of the partly occupied vehicles V1.  Their candidate pairs
are the edges of the upper bound's graph ``G`` (``find_candidates(..., bound_rules(params))``): every
pair the simulator can form is one, so nothing realisable is left out.  Each edge is valued, for both
pick-up orders (A first, B joins; a V1 passenger is always A), by the saving ``l_A + l_B - L`` (Eq. 5)
the simulator would realise given when A's vehicle drives A's shortest path P_A:

* a V1 passenger's pick-up time is known (on board: from the vehicle's position; on the way: from the
  pick-up distance of the round that assigned it);
* a waiting A takes one of the current round's vacant vehicles (pick-up after ``pk/v``; each is tried) or is
  assigned in a later round; an A not yet requested in some round of its patience.  A later
  assignment may pick a vehicle at any pick-up time in ``[0, R̄/v]`` (``plan_pickup = "range"``),
  so A's pick-up lies between the earliest round plus 0 and the last round plus ``R̄/v``;
* B joins in a round of ``[max(t_B, A's assignment + Δt), t_B + K_B]``.  While A is not on board the
  vehicle turns at ``h = o_A`` with pick-up ``l(o_A, o_B)`` (A14); afterwards at the first node ``h``
  of P_A that the vehicle can have next, inside the window, with ``pre + l(h, o_B) <= R̄`` (turning
  earlier never lengthens the route, docs/bound.md step 3).  The saving is POOL's at ``h`` with
  ``δ = l(o_A, h)``, in its best feasible service order (§1.1): :meth:`.Foresight.forecast`, with the
  V1 pick-up times of :class:`.PickupTimes` (:mod:`.foresight`, shared with ``fl-perfect``).

A maximum-weight matching of these values (``plan_solver``, an exact preset) gives every open order a
planned partner and a role: the first takes a vacant vehicle, the second joins it.  Between two plans the
pairs are kept and only the forecasts of the waiting firsts renewed (re-planning every round changed the
saving by -1.3 to +0.8 % on four peak hours at twice the time); with ``repair_s`` below ``replan_s`` a
plan one of whose pairs can no longer form (the partner decided otherwise, or the first on board with no
feasible join left) is made again once it is ``repair_s`` old.

The value of an edge whose first is not yet requested does not depend on the round (its pick-up range
is fixed under ``plan_pickup = "range"``), so it is computed once, when the edge first enters a plan's
window, and kept: a plan computes afresh only the edges of waiting and on-board firsts.

**The round** is the assignment model of MB and FL (:mod:`.candidates`, Eqs. 1-4) with utilities that
carry the plan out (``C = plan_bonus_m`` puts the plan before everything else):

* JOIN into the vehicle of the planned partner: ``C + e`` (the exact POOL saving of the round);
* VACANT pick-up of a planned first: ``C + ê(pk) - λ pk``, ``ê(pk)`` the forecast saving of its pair
  when this vehicle picks it up after ``pk/v`` (a farther vehicle can let the partner join at ``o_A``;
  ``λ = pickup_weight``); keeping it waiting ``C + ê_later - wait_margin_m`` (the forecast of a later
  assignment), so it waits only for a clear gain and never in its last round;
* a planned second waits (utility 0, no vacant option) until it can join; in its last round before
  its patience runs out it is served as an unplanned passenger;
* unplanned passengers: MB's ``e - pk`` for a join into a vehicle whose passenger is unplanned too
  (``e > 0``, A11), ``-pk`` for a vacant vehicle, offered ``now`` (as MB), in the ``last`` round of
  their patience (until then they may still be planned) or ``never`` (``unplanned``; the default: a
  solo ride saves nothing and takes a vehicle a pair may need); keeping them waiting otherwise
  ``-10⁶ m`` (A13).

After the round, and in rounds where nobody waits, idle vacant vehicles are sent towards the origins of
the orders that will need one soonest (planned firsts and unplanned orders waiting or requested within
``reposition_s``), by a minimum-total-distance assignment (:meth:`Hindsight.reposition`).

A forecast that proves wrong costs saving, never feasibility: the simulator commits only feasible
columns, and the next round re-plans from the state it reached.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from rpbench.backends import Preset, solve
from rpbench.exceptions import LookaheadError
from rpbench.model import PairingModel, Structure
from rpbench.options import Range, RunOptions, option
from rpbench.oracle.pairs import bound_rules, find_candidates
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import (
    NO_WAIT_UTILITY_M,
    VacantOptions,
    assignment_round,
    join_options,
    vacant_options,
)
from rpbench.strategies.foresight import Foresight, PickupTimes

#: Resolution of the plan's matching weights (1 cm, as the oracles').
PLAN_UNIT_M = 0.01
#: When passengers without a planned partner are served by a vacant vehicle.
UNPLANNED = ("now", "last", "never")


@dataclass(frozen=True)
class HindsightOptions(RunOptions):
    """Hindsight's options (the plan's horizon, the assumed pick-up time, the round utilities)."""

    horizon_s: float = option(
        1800.0, "the plan looks this far ahead at orders not yet requested", range=Range(0.0, 86400.0, "s")
    )
    pickup_time_s: float = option(
        150.0,
        "pick-up time assumed for orders not yet assigned, until the run's own mean is known",
        range=Range(0.0, 3600.0, "s"),
    )
    pickup_weight: float = option(
        0.0, "λ: weight of the pick-up distance in a planned first's vacant utility", range=Range(0.0, 10.0)
    )
    plan_bonus_m: float = option(
        1e5, "C: utility bonus of the columns that carry out the plan", range=Range(0.0, 1e6, "m")
    )
    reposition_s: float = option(
        300.0,
        "send idle vacant vehicles towards the orders requested within this many seconds (0: never)",
        range=Range(0.0, 3600.0, "s"),
    )
    reposition_m: float = option(
        500.0, "only vehicles farther than this from their order's origin are sent", range=Range(0.0, 1e6, "m")
    )
    plan_pickup: str = option(
        "range",
        "pick-up times a later assignment may choose: any in [0, R̄/v] (a vehicle at the right distance), "
        "or the run's mean pick-up time",
        choices=("range", "mean"),
    )
    wait_margin_m: float = option(
        200.0,
        "a planned first waits for a later assignment only when its forecast gains more than this",
        range=Range(0.0, 1e6, "m"),
    )
    unplanned: str = option(
        "never",
        "when a passenger without a planned partner gets a vacant vehicle: now (as MB), in its last round "
        "(until then it may still find a partner), or never",
        choices=UNPLANNED,
    )
    plan_solver: str = option("matching", "solver preset of the plan's maximum-weight matching (exact)")
    repair_s: float = option(
        30.0,
        "a plan one of whose pairs can no longer form is made again once it is this many seconds old",
        range=Range(0.0, 86400.0, "s"),
    )
    replan_s: float = option(
        30.0,
        "the plan's matching is made again every this many seconds; in between its pairs are kept and only "
        "their forecasts renewed",
        range=Range(0.0, 86400.0, "s"),
    )


class Hindsight(Strategy[HindsightOptions]):
    name = "hindsight"
    label = "Hindsight"
    color = "tab:brown"
    structure = Structure.ASSIGNMENT
    Options = HindsightOptions
    description = (
        "clairvoyant: a rolling maximum-weight matching of all known orders on the upper bound's pair graph, "
        "valued by forecast realised savings, carried out by the assignment model (a lower bound on OPT)"
    )
    clairvoyant = True

    def __init__(self, options: HindsightOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self._preset: Preset | None = None
        #: Pairs the rounds' plans formed (sorted order indices), for inspection and tests.
        self.planned_pairs: set[tuple[int, int]] = set()
        #: Planned first assigned a vacant vehicle -> (its planned partner, the forecast saving of the pair).
        self.commitments: dict[int, tuple[int, float]] = {}

    # ----------------------------------------------------------------- prepare
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        from rpbench.oracle.solve import resolve_preset  # the oracle imports the backends, as the simulator

        if not isinstance(scenario, Scenario):
            raise LookaheadError(
                f"strategy {self.name!r} plans with every order of the day: its prepare needs the whole scenario, "
                "not an online view"
            )
        preset = resolve_preset(self.options.plan_solver)
        # The plan's matchings are small and solved every round: without a time limit they run in-process
        # (a combinatorial preset forks a child per solve to enforce one, which costs more than the solve
        # once the process holds a city's distance table).
        self._preset = dataclasses.replace(preset, options=dataclasses.replace(preset.options, time_limit_s=None))
        o = scenario.orders
        p = scenario.params
        distances = scenario.network.distances()
        self.params = p
        self.sight = Foresight(scenario)
        # the realised orders and their round windows, as the foresight holds them
        sight = self.sight
        self.dist, self.origin, self.request, self.n = sight.dist, sight.origin, sight.request, sight.n
        self.first_round, self.last_round = sight.first_round, sight.last_round
        n = self.n
        # the upper bound's graph: every pair the simulator can form (docs/bound.md)
        cand = find_candidates(distances, o, bound_rules(p))
        lo, hi = cand.low, cand.high
        later = np.maximum(self.request[lo], self.request[hi])
        by_later = np.argsort(later, kind="stable")
        self.edge_lo, self.edge_hi = lo[by_later].astype(np.int64), hi[by_later].astype(np.int64)
        self.edge_later = later[by_later]
        self.max_patience = float(sight.patience.max()) if n else 0.0
        # what the simulator's V1 vehicles do: the pick-up time of every assigned first passenger
        self.pickups = PickupTimes(n, p.speed_mps, self.options.pickup_time_s)
        self.planned_pairs = set()
        self.commitments = {}
        self._forecasts: dict[tuple[int, int], float] = {}
        # The forecast of each edge, both pick-up orders, when its first is assigned in a later round: it
        # depends on nothing the rounds change while the first is still to be requested (the pick-up
        # range is fixed under ``plan_pickup = "range"``), so it is computed once, when the edge first
        # enters a plan's window (``_valued`` edges so far), and kept.
        self._cache_later = self.options.plan_pickup == "range"
        self._later_lo_first = np.full(len(self.edge_lo), np.nan)
        self._later_hi_first = np.full(len(self.edge_lo), np.nan)
        self._valued = 0

        #: The last plan: (its round's time, planned partner, role) of every order.
        self._kept: tuple[float, np.ndarray, np.ndarray] | None = None

    # ------------------------------------------------------------------ rounds
    def build(self, state: RoundState) -> RoundModel:
        t = state.t_s
        p = self.params
        self.pickups.observe(state)
        vac = vacant_options(state)
        join = join_options(state)
        if self._kept is None or self._plan_due(state):
            mate, first, wait_value = self._plan(state, vac)
            self._kept = (t, mate, first)
        else:
            mate, first = self._kept[1], self._kept[2]
            wait_value = self._planned_waits(state, vac, mate, first)
        p_order = state.p_order
        bonus = self.options.plan_bonus_m
        last_round = self.last_round[p_order] < t + p.dt_s - 1e-9  # cancelled before the next round

        # JOIN: a planned partner's vehicle, or MB's join when neither has a planned partner
        rider = state.v1_order[join.v]
        joiner = p_order[join.p]
        planned_join = mate[joiner] == rider
        free_join = (mate[joiner] < 0) & (mate[rider] < 0) & (join.saving_m > 0)
        keep = planned_join | free_join
        join = join.take(keep)
        planned_join = planned_join[keep]
        u_join = np.where(planned_join, bonus + join.saving_m, join.saving_m - join.pickup_m)

        # VACANT: planned firsts with a forecast of their pair; planned seconds only in their last round
        who = p_order[vac.p]
        is_first = (mate[who] >= 0) & first[who]
        is_second = (mate[who] >= 0) & ~first[who]
        unplanned = (mate[who] < 0) | (is_second & last_round[vac.p])
        serve = {"now": True, "last": last_round[vac.p], "never": is_second}[self.options.unplanned]
        offer = is_first | (unplanned & serve)
        keep_v = np.flatnonzero(offer)
        vac = VacantOptions(vac.p[keep_v], vac.v[keep_v], vac.pickup_m[keep_v])
        is_first = is_first[keep_v]
        u_vac = -vac.pickup_m.copy()
        f = np.flatnonzero(is_first)
        if len(f):
            a = p_order[vac.p[f]]
            b = mate[a]
            t_pick = t + vac.pickup_m[f] / p.speed_mps
            w = self.sight.forecast(a, b, self.sight.join_from(b, t + p.dt_s, t), self.last_round[b], t_pick)
            u_vac[f] = bonus + np.nan_to_num(w, nan=0.0) - self.options.pickup_weight * vac.pickup_m[f]
            known = np.isfinite(w)
            vehicles = state.v0_vehicle[vac.v[f]]
            keys = zip(a[known].tolist(), vehicles[known].tolist(), strict=True)
            self._forecasts = dict(zip(keys, w[known].tolist(), strict=True))
        else:
            self._forecasts = {}

        # WAIT: planned seconds wait for their partner; everyone else is served when possible (A13)
        waits = (mate[p_order] >= 0) & ~first[p_order] & ~last_round
        u_wait = np.where(waits, 0.0, NO_WAIT_UTILITY_M)
        # a planned first waits when a later assignment serves its pair better (by more than the margin)
        later = wait_value[p_order]
        delay = (mate[p_order] >= 0) & first[p_order] & ~last_round & np.isfinite(later)
        u_wait[delay] = bonus + later[delay] - self.options.wait_margin_m
        rm = assignment_round(state, vac, u_vac, join, u_join, u_wait, name=self.name)
        self.pickups.offered(t, p_order[vac.p], state.v0_vehicle[vac.v], vac.pickup_m)
        self._round_plan = (t, mate, first)
        return rm

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Idle vacant vehicles towards the origins of the orders that will need one soonest.

        The orders that need a vacant vehicle are the planned firsts and the unplanned ones (a planned
        second joins its partner's vehicle): those still waiting unassigned and those requested within
        ``reposition_s``.  Idle vehicles (not assigned in the current round) are matched to them by a
        minimum-total-distance assignment (``linear_sum_assignment``); a vehicle farther than
        ``reposition_m`` from its order's origin is sent there.
        """
        t, mate, first = self._round_plan
        self._record_commitments(rm, chosen, mate)
        busy = np.isin(state.v0_vehicle, rm.vehicle[chosen])
        served = np.isin(state.p_order, rm.first[chosen])
        return self._send_idle(state, t, mate, first, busy, served)

    def idle_moves(self, state: RoundState) -> tuple[np.ndarray, np.ndarray]:
        """In a round where nobody waits, the same moves towards the orders requested soon (the last plan's
        roles); none before the first plan."""
        if self._kept is None:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        _, mate, first = self._kept
        none = np.zeros(0, bool)
        return self._send_idle(state, state.t_s, mate, first, np.zeros(state.n_v0, bool), none)

    def _send_idle(
        self, state: RoundState, t: float, mate: np.ndarray, first: np.ndarray, busy: np.ndarray, served: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Vacant vehicles not ``busy`` towards the orders that need one: waiting ones not ``served`` in the
        current round and those requested within ``reposition_s`` (a planned second needs none)."""
        none = np.zeros(0, np.int64)
        if self.options.reposition_s <= 0 or state.n_v0 == 0:
            return none, none
        idle = np.flatnonzero(~busy)
        hi = np.searchsorted(self.request, t + self.options.reposition_s, side="right")
        lo = np.searchsorted(self.request, t, side="right")
        need = np.concatenate([state.p_order[~served], np.arange(lo, hi)])
        need = need[(mate[need] < 0) | first[need]]
        if not len(idle) or not len(need):
            return none, none
        need = need[: len(idle)]  # the soonest ones (waiting first, then by request time)
        cost = state.v0_pre_m[idle][:, None] + self.dist[state.v0_node[idle][:, None], self.origin[need][None, :]]
        rows, cols = linear_sum_assignment(cost)
        far = cost[rows, cols] > self.options.reposition_m
        return state.v0_vehicle[idle[rows[far]]].astype(np.int64), self.origin[need[cols[far]]].astype(np.int64)

    def _record_commitments(self, rm: RoundModel, chosen: np.ndarray, mate: np.ndarray) -> None:
        """Remember, for every planned first assigned in the current round, its planned partner and forecast saving."""
        c = chosen[rm.kind[chosen] == Kind.VACANT]
        for a, v in zip(rm.first[c].tolist(), rm.vehicle[c].tolist(), strict=True):
            forecast = self._forecasts.get((a, v))
            if forecast is not None:
                self.commitments[a] = (int(mate[a]), forecast)

    # -------------------------------------------------------------------- plan
    def _plan(self, state: RoundState, vac: VacantOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Planned partner (``-1``: none), role (True: picked up first) and, for a first, the forecast saving
        of its pair when it is assigned in a later round (NaN: none), of every order, in the current round."""
        t = state.t_s
        p = self.params
        n = self.n
        mate = np.full(n, -1, np.int64)
        first = np.zeros(n, bool)
        wait = np.full(n, np.nan)
        waiting, v1 = self._who(state)
        # edges whose later order is still undecided and requested within the horizon
        lo_i = np.searchsorted(self.edge_later, t - self.max_patience - p.dt_s, side="left")
        hi_i = np.searchsorted(self.edge_later, t + self.options.horizon_s, side="right")
        x, y = self.edge_lo[lo_i:hi_i], self.edge_hi[lo_i:hi_i]
        future = self.request > t
        open_ = waiting | v1 | future
        sel = open_[x] & open_[y] & ~(v1[x] & v1[y])
        x, y = x[sel], y[sel]
        if not len(x):
            return mate, first, wait
        # directed candidates (A first, B joins; the lower order first, then the higher): B is never a V1
        # passenger
        m = len(x)
        edge = np.flatnonzero(sel) + lo_i
        a = np.concatenate([x, y])
        b = np.concatenate([y, x])
        d = np.flatnonzero(~v1[b])
        lo_first = d < m
        w_d, later_d = self._edge_values(
            state, vac, a[d], b[d], np.concatenate([edge, edge])[d], lo_first, waiting, v1, int(hi_i)
        )
        w2 = np.full(2 * m, -np.inf)
        later2 = np.full(2 * m, np.nan)
        good = np.isfinite(w_d) & (w_d >= PLAN_UNIT_M)
        w2[d[good]] = w_d[good]
        later2[d] = later_d
        # the better pick-up order of each pair (a tie: the lower order first)
        higher_first = w2[m:] > w2[:m]
        w = np.where(higher_first, w2[m:], w2[:m])
        keep = np.flatnonzero(np.isfinite(w))
        if not len(keep):
            return mate, first, wait
        higher_first, w = higher_first[keep], w[keep]
        lo, hi = x[keep], y[keep]
        a, b = np.where(higher_first, hi, lo), np.where(higher_first, lo, hi)
        later = np.where(higher_first, later2[m:][keep], later2[:m][keep])
        srt = np.argsort(lo * n + hi, kind="stable")  # by (lo, hi)
        a, b, w, lo, hi, later = a[srt], b[srt], w[srt], lo[srt], hi[srt], later[srt]
        used = np.zeros(n, bool)
        used[lo] = used[hi] = True
        nodes = np.flatnonzero(used)
        index = np.zeros(n, np.int64)
        index[nodes] = np.arange(len(nodes))
        inv = np.concatenate([index[lo], index[hi]])
        model = PairingModel(
            len(nodes),
            inv[: len(lo)],
            inv[len(lo) :],
            np.floor(w / PLAN_UNIT_M),
            unit_m=PLAN_UNIT_M,
            name="hindsight-plan",
        )
        assert self._preset is not None
        chosen = solve(model, self._preset).chosen
        ca, cb = a[chosen], b[chosen]
        mate[ca], mate[cb] = cb, ca
        first[ca] = True
        wait[ca] = later[chosen]
        self.planned_pairs.update(zip(lo[chosen].tolist(), hi[chosen].tolist(), strict=True))
        return mate, first, wait

    def _plan_due(self, state: RoundState) -> bool:
        """Whether the plan is made again in the current round: the kept one is ``replan_s`` old, or
        ``repair_s`` old with one of its pairs broken (:meth:`_broken`)."""
        assert self._kept is not None
        age = state.t_s - self._kept[0]
        if age >= self.options.replan_s - 1e-9:
            return True
        if age < self.options.repair_s - 1e-9:
            return False
        return len(self._broken(state, self._kept[1], self._kept[2])) > 0

    def _broken(self, state: RoundState, mate: np.ndarray, first: np.ndarray) -> np.ndarray:
        """The open orders (waiting, on board or on the way, or not yet requested) of planned pairs that can no
        longer form: the partner decided otherwise (served alone, cancelled), or the first on board with no
        feasible join left for the second."""
        t = state.t_s
        waiting, v1 = self._who(state)
        open_ = waiting | v1 | (self.request > t)
        a = np.flatnonzero((mate >= 0) & first)
        b = mate[a]
        both, one = open_[a] & open_[b], open_[a] != open_[b]
        dead = one.copy()
        on = np.flatnonzero(both & v1[a])
        if len(on):
            dead[on] = ~np.isfinite(self._on_board_values(state, a[on], b[on]))
        loose = np.concatenate([a[dead], b[dead]])
        return loose[open_[loose]]

    def _who(self, state: RoundState) -> tuple[np.ndarray, np.ndarray]:
        """Masks over every order: waiting in the current round, and the passenger of a V1 vehicle."""
        waiting = np.zeros(self.n, bool)
        waiting[state.p_order] = True
        v1 = np.zeros(self.n, bool)
        v1[state.v1_order] = True
        return waiting, v1

    def _on_board_values(self, state: RoundState, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The forecast saving of B joining the V1 vehicle of A from the current round on (NaN: cannot)."""
        t = state.t_s
        sight = self.sight
        return sight.forecast(a, b, sight.join_from(b, t, t), self.last_round[b], self.pickups.of_v1(state, a))

    def _planned_waits(self, state: RoundState, vac: VacantOptions, mate: np.ndarray, first: np.ndarray) -> np.ndarray:
        """Between two plans: the forecast of each waiting planned first's pair when it is assigned later."""
        wait = np.full(self.n, np.nan)
        a = state.p_order[(mate[state.p_order] >= 0) & first[state.p_order]]
        if not len(a):
            return wait
        waiting, v1 = self._who(state)
        b = mate[a]
        keep = ~v1[b]
        _, later = self._pair_values(state, vac, a[keep], b[keep], waiting, v1)
        wait[a[keep]] = later
        return wait

    def _edge_values(
        self,
        state: RoundState,
        vac: VacantOptions,
        a: np.ndarray,
        b: np.ndarray,
        edge: np.ndarray,
        lo_first: np.ndarray,
        waiting: np.ndarray,
        v1: np.ndarray,
        upto: int,
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_pair_values` of the directed edges (``edge``: index in the sorted edges; ``lo_first``: its
        lower order is A), with the kept forecast of every first not yet requested (edges up to ``upto``)."""
        if not self._cache_later:
            return self._pair_values(state, vac, a, b, waiting, v1)
        self._value_edges(upto)
        w = np.where(lo_first, self._later_lo_first[edge], self._later_hi_first[edge])
        later = w.copy()
        # A waiting or on board: its vehicle and pick-up depend on the round
        i = np.flatnonzero(waiting[a] | v1[a])
        w[i], later[i] = self._pair_values(state, vac, a[i], b[i], waiting, v1)
        return w, later

    def _value_edges(self, upto: int) -> None:
        """Keep the later-assignment forecast of the sorted edges ``[_valued, upto)``, both pick-up orders."""
        k0 = self._valued
        if upto <= k0:
            return
        lo, hi = self.edge_lo[k0:upto], self.edge_hi[k0:upto]
        self._later_lo_first[k0:upto] = self._later_of(lo, hi)
        self._later_hi_first[k0:upto] = self._later_of(hi, lo)
        self._valued = upto

    def _later_of(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The forecast saving of each directed pair when A, not yet requested, is assigned in one of its
        rounds and picked up after a time in :meth:`_pickup_range_s` (NaN: cannot): what
        :meth:`_pair_values` gives such an A, in any round before A's request."""
        p = self.params
        sight = self.sight
        out = np.full(len(a), np.nan)
        r_min, r_max = self.first_round[a], self.last_round[a]
        i = np.flatnonzero(r_min <= r_max + 1e-9)
        tau_min, tau_max = self._pickup_range_s()
        out[i] = sight.forecast(
            a[i],
            b[i],
            sight.join_from(b[i], r_min[i] + p.dt_s, -np.inf),
            self.last_round[b[i]],
            r_max[i] + tau_max,
            r_min[i] + tau_min,
        )
        return out

    def _pair_values(
        self, state: RoundState, vac: VacantOptions, a: np.ndarray, b: np.ndarray, waiting: np.ndarray, v1: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The forecast saving of each directed pair (A = ``a`` first, B = ``b`` joins; NaN: cannot), and
        the forecast when A, not yet assigned, is assigned in a later round (NaN for a V1 passenger).

        A V1 passenger's vehicle is known.  A waiting A takes the current round's vacant vehicle that serves
        its pair best (``pickup_weight`` charging ``pk``) unless a later assignment gains more than
        ``wait_margin_m``; a later assignment, in any round up to A's last, picks up A after a time in
        :meth:`_pickup_range_s`.
        """
        t = state.t_s
        p = self.params
        sight = self.sight
        w = np.full(len(a), np.nan)
        later = np.full(len(a), np.nan)
        has = np.zeros(self.n, bool)
        has[state.p_order[vac.p]] = True
        t_hi = self.last_round[b]
        i = np.flatnonzero(v1[a])
        w[i] = self._on_board_values(state, a[i], b[i])
        # assigned in a later round (any up to A's last), picked up after a time in [τ_min, τ_max]
        r_min = np.where(waiting[a], t + p.dt_s, self.first_round[a])
        r_max = self.last_round[a]
        i = np.flatnonzero(~v1[a] & (r_min <= r_max + 1e-9))
        tau_min, tau_max = self._pickup_range_s()
        later[i] = sight.forecast(
            a[i], b[i], sight.join_from(b[i], r_min[i] + p.dt_s, t), t_hi[i], r_max[i] + tau_max, r_min[i] + tau_min
        )
        w[i] = later[i]
        i = np.flatnonzero(waiting[a] & has[a])
        if len(i):
            # every vacant option of A: options grouped by passenger (vacant_options is passenger-major)
            pos = np.full(self.n, -1, np.int64)
            pos[state.p_order] = np.arange(state.n_passengers)
            count = np.bincount(vac.p, minlength=state.n_passengers)
            start = np.cumsum(count) - count
            k = count[pos[a[i]]]
            rep = np.repeat(i, k)
            opt = np.repeat(start[pos[a[i]]], k) + np.arange(len(rep)) - np.repeat(np.cumsum(k) - k, k)
            pk = vac.pickup_m[opt]
            wv = sight.forecast(a[rep], b[rep], sight.join_from(b[rep], t + p.dt_s, t), t_hi[rep], t + pk / p.speed_mps)
            score = np.where(np.isfinite(wv), wv - self.options.pickup_weight * pk, -np.inf)
            best = np.lexsort((-score, rep))
            head = np.ones(len(best), bool)
            head[1:] = rep[best[1:]] != rep[best[:-1]]
            pick = best[head & np.isfinite(score[best])]
            now = np.full(len(a), np.nan)
            now[rep[pick]] = wv[pick]
            w[i] = np.fmax(now[i], later[i] - self.options.wait_margin_m)
        return w, later

    def _pickup_range_s(self) -> tuple[float, float]:
        """The pick-up times a later assignment is assumed to choose among (``plan_pickup``)."""
        tau = self.pickups.mean_s()
        if self.options.plan_pickup == "mean":
            return tau, tau
        return 0.0, self.params.max_pickup_m / self.params.speed_mps
