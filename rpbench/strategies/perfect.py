"""FL-perfect: FL with perfect information, which splits FL's distance to the optimum into prediction and structure.

FL's round exactly (:func:`.forward.forward_round`, Eqs. 13-14: MB's options, joins only with ``e > 0``
(A11), ``ē²/(ē+pk)·α^k_p`` for a vacant vehicle, ``e²/(e+pk)·α^k_p`` for a join, ``ē(0,p) - l̄`` for
waiting, τ_0 and l̄ from the MB calibration run), with the two predicted expected savings of the
seeker/taker model replaced by what the realised orders give.  It reads the future, so it is
clairvoyant.  A pair is valued by :meth:`.Foresight.forecast`: the saving ``l_A + l_B - L`` (Eq. 5) the
simulator would realise with A picked up at a given time and B joining in a round of a given window, at
the first node of A's path the vehicle can have next with pick-up ``<= R̄``.  Each value is one order's
best partner, ignoring competition for it.  With ``t`` the round, ``first``/``last`` an order's first
and last round, τ_0 FL's sojourn of the origin state (A4; rounded to 10 s as FL's prediction uses it):

* ``ē*(p)`` for ``ē(p)`` (Eq. 9; p a taker): the largest positive forecast over orders B not yet
  revealed (requested after ``t``), p picked up at ``t + τ_0``, B joining in ``[max(first_B, t + Δt),
  last_B]``; 0 when there is none.
* ``ē*(0,p)`` for ``ē(0,p)`` (Eq. 10): ``[1 - (1 - r_w)^{n_rem}] · max(ē*_s(p), ē*_later(p))``, FL's
  factor (``n_rem = max(0, ⌊K̄/Δt⌋ - k_p)``, the planner's K̄, A10) with the bracket ``p_s ē(s) + (1 -
  p_s) ē(p)`` replaced by the better realised outcome of waiting, each 0 when no forecast is positive:

  - ``ē*_s(p)`` (p a seeker, for ``ē(s)``): the largest forecast of p joining, in ``[r_A + Δt,
    last_p]``, the vehicle of a first passenger A that is a V1 passenger (picked up when
    :class:`.PickupTimes` says; ``r_A = t``), another waiting passenger (assigned now, ``r_A = t``,
    picked up at ``t + τ_0``) or an order not yet revealed (assigned in its first round ``r_A =
    first_A``, picked up at ``r_A + τ_0``): the taker states a seeker meets in the prediction;
  - ``ē*_later(p)`` (p a taker later, for ``ē(p)``): the largest forecast of an order B not yet
    revealed joining p's vehicle when p is assigned in a later round of its patience, picked up at any
    time in ``[t + Δt + τ_0, last_p + τ_0]``, B joining in ``[max(first_B, t + 2Δt), last_B]``.

The windows use each order's realised patience (the simulator's rule); FL's factor keeps the planner's K̄.
Everything else is FL's, so ``FL-perfect - FL`` is what perfect values are worth to FL's structure and
``Hindsight - FL-perfect`` what that structure leaves (docs/prediction.md, "Perfect information: fl-perfect").

Options (``--opt fl-perfect.NAME=VALUE``): ``order_rule``, ``tau0_s`` and ``mean_pickup_m``, as FL's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rpbench.exceptions import LookaheadError
from rpbench.model import Structure
from rpbench.predict.hourly import TAU0_RESOLUTION_S
from rpbench.predict.savings import waiting_saving
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy
from rpbench.strategies.foresight import Foresight, PickupTimes
from rpbench.strategies.forward import (
    FALLBACK_MEAN_PICKUP_M,
    FALLBACK_TAU0_S,
    CalibratedOptions,
    MBCalibrated,
    _per_hour,
    forward_options,
    forward_round,
)


@dataclass(frozen=True)
class PerfectOptions(CalibratedOptions):
    """FL-perfect's options: FL's that do not concern the prediction."""


@dataclass(frozen=True)
class PerfectValues:
    """The realised values of a round's waiting passengers (state order, metres)."""

    taker: np.ndarray  # ē*(p)
    seeker: np.ndarray  # ē*_s(p)
    later: np.ndarray  # ē*_later(p)
    wait: np.ndarray  # ē*(0,p)


class ForwardPerfect(MBCalibrated, Strategy[PerfectOptions]):
    name = "fl-perfect"
    label = "FL-perfect"
    color = "tab:cyan"
    structure = Structure.ASSIGNMENT
    Options = PerfectOptions
    description = (
        "clairvoyant: FL, paper Eqs. (13)-(14), with ē(p) and ē(0,p) computed from the realised orders "
        "(each order's best partner) instead of predicted"
    )
    clairvoyant = True

    def __init__(self, options: PerfectOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.tau0_s: np.ndarray = np.array([FALLBACK_TAU0_S])
        self.mean_pickup_m: np.ndarray = np.array([FALLBACK_MEAN_PICKUP_M])

    # ----------------------------------------------------------- prepare
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        if not isinstance(scenario, Scenario):
            raise LookaheadError(
                f"strategy {self.name!r} values passengers by the realised orders: its prepare needs the whole "
                "scenario, not an online view"
            )
        hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
        tau0 = _per_hour(self.options.tau0_s, hours, FALLBACK_TAU0_S, "tau0_s")
        # the sojourn FL's prediction is solved with (scenario_predictions rounds it so)
        self.tau0_s = np.maximum(TAU0_RESOLUTION_S, np.round(tau0 / TAU0_RESOLUTION_S) * TAU0_RESOLUTION_S)
        self.mean_pickup_m = _per_hour(self.options.mean_pickup_m, hours, FALLBACK_MEAN_PICKUP_M, "mean_pickup_m")
        self.sight = Foresight(scenario)
        self.pickups = PickupTimes(self.sight.n, scenario.params.speed_mps, float(self.tau0_s[0]))

    def _hour(self, t_s: float) -> int:
        return min(int(t_s // 3600.0), len(self.tau0_s) - 1)

    # ------------------------------------------------------------------ rounds
    def build(self, state: RoundState) -> RoundModel:
        self.pickups.observe(state)
        vac, join = forward_options(state, self.options.order_rule)
        values = self.values(state)
        mean_pickup_m = float(self.mean_pickup_m[min(self._hour(state.t_s), len(self.mean_pickup_m) - 1)])
        rm = forward_round(state, vac, join, values.taker, values.wait, mean_pickup_m, name=self.name)
        offered = rm.kind == Kind.VACANT
        self.pickups.offered(state.t_s, rm.first[offered], rm.vehicle[offered], rm.pickup_m[offered])
        return rm

    def values(self, state: RoundState) -> PerfectValues:
        """ē*(p), ē*_s(p), ē*_later(p) and ē*(0,p) of the round's waiting passengers (module docstring)."""
        sight, p = self.sight, state.params
        t, dt, v = state.t_s, p.dt_s, p.speed_mps
        tau0 = float(self.tau0_s[self._hour(t)])
        me = np.asarray(state.p_order, np.int64)
        n_p = len(me)
        last = sight.last_round[me]
        start = int(np.searchsorted(sight.request, t, side="right"))  # the orders not yet revealed
        # p a taker, now or later: partners revealed before p's vehicle can reach its destination
        reach = last + tau0 + sight.solo[me] / v
        stop = int(np.searchsorted(sight.request, reach.max(initial=t), side="right"))
        i, b = _pairs(n_p, np.arange(start, stop, dtype=np.int64))
        near = sight.first_round[b] <= reach[i] + 1e-6
        i, b = i[near], b[near]
        a = me[i]
        now = np.full(len(b), t + tau0)
        taker = _best(n_p, i, sight.forecast(a, b, sight.join_from(b, t + dt, t), sight.last_round[b], now))
        soon = t + dt <= last[i] + 1e-9  # p has a later round
        i, a, b, early = i[soon], a[soon], b[soon], now[soon] + dt
        later = sight.forecast(a, b, sight.join_from(b, t + 2 * dt, t), sight.last_round[b], last[i] + tau0, early)
        later = _best(n_p, i, later)
        # p a seeker: the first passengers of V1 vehicles, the other waiting ones, orders revealed in time
        stop = int(np.searchsorted(sight.request, last.max(initial=t) - dt, side="right"))
        coming = np.arange(start, max(start, stop), dtype=np.int64)
        firsts = np.concatenate([np.asarray(state.v1_order, np.int64), me, coming])
        assigned = np.concatenate([np.full(state.n_v1 + n_p, t), sight.first_round[coming]])
        picked = np.concatenate(
            [self.pickups.of_v1(state, state.v1_order), np.full(n_p, t + tau0), sight.first_round[coming] + tau0]
        )
        i, k = _pairs(n_p, np.arange(len(firsts)))
        keep = (firsts[k] != me[i]) & (assigned[k] + dt <= last[i] + 1e-9)
        i, k = i[keep], k[keep]
        joins = sight.join_from(me[i], assigned[k] + dt, t)
        seeker = _best(n_p, i, sight.forecast(firsts[k], me[i], joins, last[i], picked[k]))
        wait = waiting_saving(
            np.maximum(seeker, later),
            state.p_rounds_waited,
            planner_patience_s=p.planner_patience_s,
            dt_s=dt,
            response_rate=p.response_rate,
        )
        return PerfectValues(taker=taker, seeker=seeker, later=later, wait=wait)


def _pairs(n: int, others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every (passenger position, other) combination, passenger-major."""
    return np.repeat(np.arange(n), len(others)), np.tile(others, n)


def _best(n: int, who: np.ndarray, saving: np.ndarray) -> np.ndarray:
    """Per passenger, the largest positive saving (0: none; NaN: the pair cannot form)."""
    out = np.zeros(n)
    np.maximum.at(out, who, np.nan_to_num(saving, nan=0.0))
    return out
