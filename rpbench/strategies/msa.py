"""MSA: sampled futures with consensus, the multiple scenario approach on the batch round (docs/sampling.md).

Bent & Van Hentenryck's multiple scenario approach (Operations Research 52(6), 2004) decides online by
sampling: each round, draw S possible futures from what is known of the demand, solve each as an offline
problem, and act on what most of them agree on.  The decision here is, for every waiting passenger p,
whether to offer p a vacant vehicle in the current round (``now``) or to keep p for a partner's vehicle
(``wait``); the round itself is MB's assignment (Eqs. 1-4, utilities of Eq. 7), so the simulator, the
checker and every backend treat MSA like any strategy.

**A future** ω_s (s = 1..S) holds the waiting passengers, the passengers of the partly occupied vehicles V1,
and the orders sampled for ``(t, t + H]``: per OD w a Poisson process at the current hour's rate ν·λ_w
(:func:`rpbench.predict.hourly.hourly_rates`, the demand known before the day that FL's prediction reads;
a history pooled over zones is sampled at the zones' representative nodes).  All S futures are drawn at
once from one random stream, seeded by the option ``seed`` and the scenario's seed::

    (MSA-1)  N_s ~ Poisson(ν Λ H),  each order of OD w with probability λ_w / Λ at a uniform time,  Λ = Σ_w λ_w
             ν = 1 (volume = table),  or  ν(t) = (N(t) + Λ H) / (E(t) + Λ H)  (volume = observed)

with N(t) the orders revealed to the strategy so far and E(t) = ∫_0^t Λ the table's expected count: a
table of the whole demand (Haikou's 21-day table, 3,110 orders an hour) then drives a 30 % sample at its
own level, and a history of the right level keeps ν near 1.

**The offline problem of a future** is a maximum-weight matching over the pairs the simulator could form,
each weighted by the saving it would realise.  The simulator pools two passengers one way only: the first,
A, takes a vacant vehicle, and the second, B, joins A's vehicle in a later round (the assignment cannot
pair two waiting passengers in one round, §2.8).  So a pair is directed, and its saving is the clairvoyant
planners' forecast (:meth:`~.foresight.Foresight.forecast`, here on the sampled orders): A is dispatched
now if it is waiting, in the round that reveals it if it is sampled; it is picked up after the drive of
its nearest vacant vehicle (a waiting A) or the run's mean of those drives (a sampled A), then drives its
shortest path; B joins in a round of ``[A's dispatch + Δt, B's last round]`` (patience K̄, A10) at the
first node where ``pk <= R̄`` and both detours ``<= D̄`` (before A's pick-up at h = o_A, A14), its saving
``e = l_A + l_B - L`` (Eq. 5, §1.1).  Pairs with ``e <= 0`` are left out (A11).  A V1 passenger is an A
dispatched already; it pairs with a waiting B at the saving of the current round's join option.  An unordered
pair weighs its better orientation.

**The vote of a future** for a waiting p, from its matching M_s: ``now`` when p is unmatched or is the A of
its pair (its vehicle must leave for B to join it); ``wait`` when p is the B (it joins its partner's
vehicle: a V1 vehicle now, a waiting partner's next round, a sampled partner's once it is dispatched).
Voting by role, rather than by whether the partner is sampled, is what the simulator can carry out: a
waiting pair needs its A dispatched and its B held back.  A passenger in its last round (no later round
within K̄) never waits.

* ``rule = consensus``: p waits when more than half of the S futures vote wait.
* ``rule = regret``: p waits when deciding now loses more saving over the futures than waiting,
  ``Σ_s loss_s(p, now) > Σ_s loss_s(p, wait)``, with::

    (MSA-2)  loss_s(p, d) = 0   when p is unmatched in M_s, or M_s's vote for p is d; otherwise
             loss_s(p, d) = w(p, m) - max(0, max_{q ∈ U_s ∪ {m}} w_d(p, q), max_{q ∈ U_s} w(m, q))

  m p's partner in M_s, U_s the orders M_s leaves unmatched, w(x, y) a pair's weight and w_d(p, q) the
  saving of (p, q) in the orientation d stands for (now: p first; wait: q first, p joins).  M_s without
  p's pair, plus the best single pair that re-pairs p under d or its partner m, is a matching that
  respects d: ``loss_s`` bounds the exact regret ``V(M_s) - max{V(M) : M respects d}`` from above, the
  one-swap sub-optimality approximation of the regret algorithm.

**The decoding** is MB's round: a ``now`` passenger has its vacant options at ``-pk``, its joins at
``e - pk`` and keep-waiting at ``NO_WAIT_UTILITY_M`` (A13); a ``wait`` passenger has no vacant option, its
joins with ``e > 0`` at ``e - pk`` and keep-waiting at ``NO_WAIT_UTILITY_M``.

Options (``--opt msa.NAME=VALUE``): ``samples`` (S), ``horizon_s`` (H), ``rule``, ``seed``, ``volume``,
``order_rule`` (of the round's join options, §1.1, A6).  What it reads: in ``prepare`` the
:class:`~rpbench.scenarios.base.OnlineView` (network, parameters, seed, demand history), then each round's
``RoundState``; never the realised orders.  A scenario without a demand history (the 2017-07-01 trace) has
nothing to sample from: ``prepare`` says so.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from rpbench.backends import Preset, load_preset, solve
from rpbench.exceptions import ParameterError
from rpbench.model import PairingModel, Structure
from rpbench.options import Range, option
from rpbench.predict.hourly import history_zone_m, hourly_rates, reads_realised_orders
from rpbench.predict.rates import OdRates
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.scenarios.common import make_orders
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import (
    JoinOptions,
    VacantOptions,
    join_options,
    vacant_options,
)
from rpbench.strategies.foresight import Foresight
from rpbench.strategies.myopic import PoolingOptions, mb_round
from rpbench.units import HOUR_S

#: How the futures' votes become a decision.
MSA_RULES = ("consensus", "regret")
#: The demand level of the sampled futures: the rate table's own, or scaled to the orders revealed so far.
MSA_VOLUMES = ("table", "observed")
#: Resolution of the futures' matching weights (10 cm: savings of tens of km stay exact for PyMatching).
_UNIT_M = 0.1
#: The exact matching preset of the futures (run in-process: the matchings are small).
_PRESET = "matching"
#: Slack on round boundaries: an arrival exactly at a round's time is revealed in that round.
_EPS = 1e-9


@dataclass(frozen=True)
class SamplingOptions(PoolingOptions):
    """MSA's options: how many futures, how far ahead, how they decide, their seed, their demand level."""

    samples: int = option(8, "S: futures sampled and solved per round", range=Range(1, 256, integer=True))
    horizon_s: float = option(
        300.0, "H: each future holds the orders sampled for the next H seconds", range=Range(0.0, 3600.0, "s")
    )
    rule: str = option(
        "consensus",
        "a passenger waits when most futures vote wait (consensus) or when deciding now loses more saving on "
        "average than waiting (regret)",
        choices=MSA_RULES,
    )
    seed: int = option(
        0, "seed of the futures, combined with the scenario's seed", range=Range(0, 2**32 - 1, integer=True)
    )
    volume: str = option(
        "observed",
        "demand level of the futures: the rate table's (table) or scaled to the orders revealed so far (observed)",
        choices=MSA_VOLUMES,
    )


@dataclass(frozen=True, eq=False)
class Futures:
    """The orders sampled for one round, all futures together, grouped by future and by time within one."""

    future: np.ndarray  # int64: which future (0..S-1), non-decreasing
    origin: np.ndarray  # int64 node index
    destination: np.ndarray
    arrival_s: np.ndarray  # float64 request time in (t, t + H]

    def __len__(self) -> int:
        return len(self.future)


@dataclass(frozen=True, eq=False)
class Votes:
    """What the futures of one round said, per waiting passenger (state order)."""

    wait_votes: np.ndarray  # int64: futures voting wait
    loss_now: np.ndarray  # float64: mean saving lost by deciding now (MSA-2), m
    loss_wait: np.ndarray  # float64: mean saving lost by waiting, m
    last_round: np.ndarray  # bool: no later round within K̄; never waits
    wait: np.ndarray  # bool: the decision


class MultipleScenario(Strategy[SamplingOptions]):
    name = "msa"
    label = "MSA"
    color = "tab:red"
    structure = Structure.ASSIGNMENT
    Options = SamplingOptions
    description = (
        "multiple scenario approach: sample S futures from the demand rates, solve each as a maximum-weight "
        "pairing, keep a passenger waiting where the futures agree it will join a partner"
    )

    def __init__(self, options: SamplingOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.rates: list[OdRates] = []
        self._cdf: dict[int, np.ndarray] = {}
        self._rng = np.random.default_rng()
        self._seen: set[int] = set()
        self._preset: Preset | None = None
        self._view: OnlineView | Scenario | None = None
        self._pickup_sum_m = 0.0
        self._pickup_count = 0
        #: The last round's votes and decision, for inspection and tests.
        self.votes: Votes | None = None

    # ----------------------------------------------------------------- prepare
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        """Load the hourly rates λ_w the futures are drawn from (the demand known before the day) and seed
        the one random stream of the run from ``seed`` and the scenario's seed."""
        if reads_realised_orders("auto", scenario.demand):
            raise ParameterError(
                f"strategy 'msa' samples its futures from the demand known before the day; scenario "
                f"{scenario.name!r} has no demand table or history: run msa on a scenario with one "
                "(haikou-peak, haikou-day, toy, lattice, a city's)"
            )
        hours = max(1, int(np.ceil(scenario.horizon_s / HOUR_S)))
        zone = history_zone_m("auto", scenario.demand)
        self.rates = hourly_rates(scenario, "auto", hours, zone)
        self._cdf = {}
        self._rng = np.random.default_rng([int(self.options.seed), int(scenario.seed)])
        self._seen = set()
        preset = load_preset(_PRESET)
        # without a time limit the small matchings run in-process (a limit forks a child per solve)
        self._preset = dataclasses.replace(preset, options=dataclasses.replace(preset.options, time_limit_s=None))
        self._view = scenario
        self._pickup_sum_m, self._pickup_count = 0.0, 0
        self.votes = None

    # ------------------------------------------------------------------ rounds
    def build(self, state: RoundState) -> RoundModel:
        self._seen.update(state.p_order.tolist())
        vac = vacant_options(state)
        join = join_options(state, self.options.order_rule)
        self.votes = self.decide(state, vac, join)
        return msa_round(state, vac, join, self.votes.wait, name=self.name)

    def decide(self, state: RoundState, vac: VacantOptions, join: JoinOptions) -> Votes:
        """Sample the futures, solve each, and turn their votes into each waiting passenger's decision."""
        p = state.params
        # no later round within K̄ (A10): the simulator may cancel it before the next round
        last = state.t_s + p.dt_s > state.p_request_s + p.planner_patience_s + _EPS
        futures = self.sample(state.t_s)
        pickup_s = self.pickup_times(state, vac)
        assert self._view is not None and self._preset is not None, "prepare() runs before the first round"
        sampled = sampled_scenario(self._view, state, futures)
        graph = _FutureGraph.build(state, join, futures, sampled, pickup_s, self.options.samples)
        wait_vote, loss_now, loss_wait = graph.votes(graph.solve(self._preset))
        if self.options.rule == "consensus":
            wait = wait_vote.sum(axis=0) * 2 > self.options.samples
        else:
            wait = loss_now.mean(axis=0) > loss_wait.mean(axis=0)
        return Votes(
            wait_votes=wait_vote.sum(axis=0).astype(np.int64),
            loss_now=loss_now.mean(axis=0),
            loss_wait=loss_wait.mean(axis=0),
            last_round=last,
            wait=wait & ~last,
        )

    def pickup_times(self, state: RoundState, vac: VacantOptions) -> tuple[np.ndarray, float]:
        """When a first passenger dispatched now is picked up: each waiting passenger after the drive of its
        nearest vacant vehicle; one of a future, after the mean of those drives over the run so far (R̄/2
        before any is seen)."""
        v = state.params.speed_mps
        nearest = np.full(state.n_passengers, np.inf)
        np.minimum.at(nearest, vac.p, vac.pickup_m)
        seen = np.isfinite(nearest)
        self._pickup_sum_m += float(nearest[seen].sum())
        self._pickup_count += int(seen.sum())
        mean_m = self._pickup_sum_m / self._pickup_count if self._pickup_count else state.params.max_pickup_m / 2
        return np.where(seen, nearest, mean_m) / v, mean_m / v

    # ----------------------------------------------------------------- futures
    def sample(self, t_s: float) -> Futures:
        """The orders of S futures over ``(t, t + H]``: per future, ``Poisson(ν Λ H)`` arrivals, each of OD w
        with probability ``λ_w / Λ`` at a uniform time (a Poisson process per OD, drawn as one)."""
        s, horizon = self.options.samples, self.options.horizon_s
        hour = min(int(t_s // HOUR_S), len(self.rates) - 1)
        rates = self.rates[hour]
        total = rates.total_per_s
        if total <= 0 or horizon <= 0:
            empty = np.zeros(0, np.int64)
            return Futures(empty, empty, empty, np.zeros(0))
        mean = self.volume_factor(t_s) * total * horizon
        counts = self._rng.poisson(mean, size=s)
        future = np.repeat(np.arange(s, dtype=np.int64), counts)
        cdf = self._cdf.get(id(rates))
        if cdf is None:
            cdf = np.cumsum(rates.rate_per_s) / total
            self._cdf[id(rates)] = cdf
        od = np.minimum(np.searchsorted(cdf, self._rng.random(len(future)), side="right"), len(cdf) - 1)
        arrival = t_s + horizon * (1.0 - self._rng.random(len(future)))  # (t, t + H]
        order = np.lexsort((arrival, future))
        od, arrival = od[order], arrival[order]
        return Futures(
            future,
            rates.origin[od].astype(np.int64),
            rates.destination[od].astype(np.int64),
            arrival,
        )

    def volume_factor(self, t_s: float) -> float:
        """ν(t) of (MSA-1): 1 with ``volume = table``; else the orders revealed so far against the table's
        expected count, with one horizon of the table's demand as a prior (ν = 1 at the start)."""
        if self.options.volume == "table":
            return 1.0
        totals = np.array([r.total_per_s for r in self.rates])
        hour = min(int(t_s // HOUR_S), len(totals) - 1)
        # E(t): the hours before the current one, then the part of the current one (the last hour goes on)
        expected = float(totals[:hour].sum() * HOUR_S + totals[hour] * (t_s - hour * HOUR_S))
        prior = float(totals[hour] * self.options.horizon_s)
        if prior + expected <= 0:
            return 1.0
        return (len(self._seen) + prior) / (expected + prior)


def msa_round(state: RoundState, vac: VacantOptions, join: JoinOptions, wait: np.ndarray, *, name: str) -> RoundModel:
    """MB's round (Eq. 7) with the decisions: a waiting passenger has no vacant option and only joins that
    save distance (``e > 0``, A11); every passenger's keep-waiting utility is ``NO_WAIT_UTILITY_M`` (A13)."""
    keep_v = np.flatnonzero(~wait[vac.p])
    vac = VacantOptions(vac.p[keep_v], vac.v[keep_v], vac.pickup_m[keep_v])
    join = join.take(~wait[join.p] | (join.saving_m > 0))
    return mb_round(state, vac, join, name=name)


# --------------------------------------------------------------------------- the futures' pairing
def sampled_scenario(view: OnlineView | Scenario, state: RoundState, futures: Futures) -> tuple[Scenario, np.ndarray]:
    """The round's orders of every future as one scenario (the waiting passengers, then the sampled orders,
    each with the planner's patience K̄, A10), and each one's row in it (rows are sorted by request time)."""
    params = state.params
    request = np.concatenate([state.p_request_s, futures.arrival_s])
    origin = np.concatenate([state.p_origin, futures.origin])
    destination = np.concatenate([state.p_destination, futures.destination])
    order = np.argsort(request, kind="stable")
    row = np.empty(len(order), np.int64)
    row[order] = np.arange(len(order))
    orders = make_orders(
        np.arange(len(order)),
        request[order],
        origin[order].astype(np.int32),
        destination[order].astype(np.int32),
        np.full(len(order), params.planner_patience_s),
    )
    scenario = Scenario(
        name=f"{view.name}-sampled",
        label=f"sampled futures of {view.label}",
        network=view.network,
        orders=orders,
        fleet=view.fleet,
        params=params,
        seed=view.seed,
        horizon_s=view.horizon_s,
        start_time=view.start_time,
        synthetic=True,
    )
    return scenario, row


@dataclass(frozen=True, eq=False)
class _Edges:
    """Unordered pairs ``x < y`` of the futures' nodes: ``w_x`` the saving with x picked up first (A) and y
    joining (B), NaN where the simulator cannot form it; ``w_y`` the other way round."""

    x: np.ndarray
    y: np.ndarray
    w_x: np.ndarray
    w_y: np.ndarray

    @classmethod
    def concat(cls, parts: list[_Edges]) -> _Edges:
        if not parts:
            none = np.zeros(0, np.int64)
            return cls(none, none, np.zeros(0), np.zeros(0))
        return cls(*(np.concatenate([getattr(e, f.name) for e in parts]) for f in dataclasses.fields(cls)))

    @classmethod
    def formable(cls, x, y, w_x, w_y) -> _Edges:
        """The pairs with a formable orientation (a finite saving) among ``(x, y)``."""
        keep = np.isfinite(w_x) | np.isfinite(w_y)
        return cls(x[keep], y[keep], w_x[keep], w_y[keep])

    def shifted(self, by: int) -> _Edges:
        return _Edges(self.x + by, self.y + by, self.w_x, self.w_y)

    def weight(self) -> np.ndarray:
        """The pair's weight: its better orientation."""
        return np.fmax(self.w_x, self.w_y)

    def x_first(self) -> np.ndarray:
        """Whether the weight's orientation picks x up first (ties: x)."""
        return ~(self.w_y > self.w_x) & np.isfinite(self.w_x)


@dataclass(frozen=True, eq=False)
class _Dispatch:
    """The future orders as the forecast sees them: row in the sampled scenario, when each is dispatched
    as a first passenger (A) and when it is then picked up."""

    row: np.ndarray
    dispatch_s: np.ndarray
    pick_s: np.ndarray


def _both_ways(sight: Foresight, t_s: float, dt_s: float, orders: _Dispatch, x, y) -> tuple[np.ndarray, np.ndarray]:
    """The saving of each pair ``(orders[x], orders[y])`` with x picked up first and y joining, and the other
    way round: B joins A's vehicle (A dispatched at ``dispatch_s``) in a round after A's dispatch and within
    B's patience (:meth:`~.foresight.Foresight.forecast`); NaN where it cannot or saves nothing (A11).  One
    forecast for every pair and both orientations: its walk along the paths is one numpy step per node."""
    a, b = np.concatenate([x, y]), np.concatenate([y, x])
    if not len(a):
        return np.zeros(0), np.zeros(0)
    rb = orders.row[b]
    t_lo = sight.join_from(rb, orders.dispatch_s[a] + dt_s, t_s)
    w = sight.forecast(orders.row[a], rb, t_lo, sight.last_round[rb], orders.pick_s[a])
    w = np.where(w > 0, w, np.nan)
    return w[: len(x)], w[len(x) :]


@dataclass(frozen=True, eq=False)
class _FutureGraph:
    """The S futures' pairings as one graph of S disjoint blocks, solved by one maximum-weight matching.

    Block s holds the n waiting passengers (nodes ``block[s] .. block[s] + n - 1``, in state order), then the
    V1 passengers, then future s's sampled orders.  The pairs among the waiting passengers and with the V1
    passengers do not depend on the future: they are forecast once and copied into every block.
    """

    n_waiting: int
    block: np.ndarray  # first node of each block, and the node count last (S + 1 entries)
    edges: _Edges

    @classmethod
    def build(
        cls,
        state: RoundState,
        join: JoinOptions,
        futures: Futures,
        sampled: tuple[Scenario, np.ndarray],
        pickup_s: tuple[np.ndarray, float],
        samples: int,
    ) -> _FutureGraph:
        scenario, row = sampled
        sight = Foresight(scenario)
        t, dt = state.t_s, state.params.dt_s
        n, r, m = state.n_passengers, state.n_v1, len(futures)
        counts = np.bincount(futures.future, minlength=samples)
        block = np.concatenate([[0], np.cumsum(n + r + counts)]).astype(np.int64)
        # the waiting passengers, then the sampled orders: a waiting A is dispatched now, a sampled one in the
        # round that reveals it
        first = sight.first_round[row[n:]]
        dispatch = np.concatenate([np.full(n, t), first])
        orders = _Dispatch(row, dispatch, dispatch + np.concatenate([pickup_s[0], np.full(m, pickup_s[1])]))
        # candidate pairs as rows of `orders`: among the waiting passengers, of a waiting passenger with every
        # sampled order, and among the sampled orders of one future
        i, j = (k.astype(np.int64) for k in np.triu_indices(n, k=1))
        p, a = (k.ravel().astype(np.int64) for k in np.meshgrid(np.arange(n), np.arange(m), indexing="ij"))
        c, d = _same_future(futures.future, counts)
        groups = [(i, j), (p, n + a), (n + c, n + d)]
        x, y = (np.concatenate([g[k] for g in groups]) for k in (0, 1))
        cut = np.cumsum([len(g[0]) for g in groups])[:-1]
        (wx_among, wx_with, wx_sampled), (wy_among, wy_with, wy_sampled) = (
            np.split(w, cut) for w in _both_ways(sight, t, dt, orders, x, y)
        )
        # ... as nodes of the graph: the pairs among the waiting passengers (and with V1) in every block
        start = np.cumsum(counts) - counts
        node = block[futures.future] + n + r + np.arange(m) - start[futures.future]
        shared = _Edges.concat([_Edges.formable(i, j, wx_among, wy_among), _rider_edges(n, join)])
        parts = [shared.shifted(int(b)) for b in block[:-1]]
        parts.append(_Edges.formable(block[futures.future[a]] + p, node[a], wx_with, wy_with))
        parts.append(_Edges.formable(node[c], node[d], wx_sampled, wy_sampled))
        return cls(n, block, _Edges.concat(parts))

    def solve(self, preset: Preset) -> np.ndarray:
        """The chosen edge of every node (-1: unmatched) in a maximum-weight matching of all blocks."""
        e = self.edges
        chosen_edge = np.full(int(self.block[-1]), -1, np.int64)
        values = np.floor(e.weight() / _UNIT_M)
        cols = np.flatnonzero(values >= 1)
        if not len(cols):
            return chosen_edge
        model = PairingModel(
            int(self.block[-1]), e.x[cols], e.y[cols], values[cols], unit_m=_UNIT_M, name="msa-futures"
        )
        chosen = cols[solve(model, preset).chosen]
        chosen_edge[e.x[chosen]] = chosen
        chosen_edge[e.y[chosen]] = chosen
        return chosen_edge

    def votes(self, chosen_edge: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per future and waiting passenger (S x n): whether it votes wait (it is the B of its pair), and the
        saving lost (MSA-2) by deciding now and by waiting."""
        e, n = self.edges, self.n_waiting
        shape = (len(self.block) - 1, n)
        if not len(e.x):  # nothing to pair: every future votes now
            return np.zeros(shape, bool), np.zeros(shape), np.zeros(shape)
        weight = e.weight()
        node = (self.block[:-1, None] + np.arange(n)[None, :]).ravel()
        edge = chosen_edge[node]
        matched = edge >= 0
        k = np.where(matched, edge, 0)
        is_x = e.x[k] == node
        partner = np.where(is_x, e.y[k], e.x[k])
        first = np.where(is_x, e.x_first()[k], ~e.x_first()[k])
        wait = matched & ~first
        # the best single pair a one-swap repair restores under the other decision
        free = chosen_edge < 0
        as_a, as_b = _best_with_role(e, chosen_edge, free)
        keep_partner = _best_with_free(e, weight, free)[np.where(matched, partner, 0)]
        w = np.where(matched, weight[k], 0.0)
        repair_now = np.fmax(np.fmax(as_a[node], keep_partner), 0.0)
        repair_wait = np.fmax(np.fmax(as_b[node], keep_partner), 0.0)
        loss_now = np.where(wait, np.maximum(w - repair_now, 0.0), 0.0)
        loss_wait = np.where(matched & first, np.maximum(w - repair_wait, 0.0), 0.0)
        return wait.reshape(shape), loss_now.reshape(shape), loss_wait.reshape(shape)


def _rider_edges(n: int, join: JoinOptions) -> _Edges:
    """V1 passengers (node ``n + v``: an A dispatched already) with the waiting B of the current round's join options
    that save distance, at the join's saving."""
    good = np.flatnonzero(join.saving_m > 0)
    return _Edges(join.p[good], n + join.v[good], np.full(len(good), np.nan), join.saving_m[good])


def _same_future(future: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every pair ``a < b`` of sampled orders of one future (orders grouped by future)."""
    end = (np.cumsum(counts))[future]
    count = end - np.arange(len(future)) - 1
    a = np.repeat(np.arange(len(future), dtype=np.int64), count)
    b = a + 1 + np.arange(len(a)) - np.repeat(np.cumsum(count) - count, count)
    return a, b


def _best_with_role(e: _Edges, chosen_edge: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per node p, the best pair of p with a partner the matching leaves free (unmatched, or p's own
    partner): with p picked up first (deciding now) and with p joining (waiting); -inf where none."""
    as_a = np.full(len(chosen_edge), -np.inf)
    as_b = np.full(len(chosen_edge), -np.inf)
    own = np.arange(len(e.x))
    for me, other, w_me, w_other in ((e.x, e.y, e.w_x, e.w_y), (e.y, e.x, e.w_y, e.w_x)):
        ok = free[other] | (chosen_edge[me] == own)
        np.maximum.at(as_a, me, np.where(ok & np.isfinite(w_me), w_me, -np.inf))
        np.maximum.at(as_b, me, np.where(ok & np.isfinite(w_other), w_other, -np.inf))
    return as_a, as_b


def _best_with_free(e: _Edges, weight: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Per node, the best pair with a partner the matching leaves unmatched; -inf where none."""
    best = np.full(len(free), -np.inf)
    np.maximum.at(best, e.x, np.where(free[e.y], weight, -np.inf))
    np.maximum.at(best, e.y, np.where(free[e.x], weight, -np.inf))
    return best
