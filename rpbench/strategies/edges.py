"""A round as a list of candidate edges, for a dispatcher that is not a Python strategy: what it is shown,
and how its answer becomes the round's model.

Every waiting passenger p has, in this order, its **vacant** edges (p, a vacant vehicle within R̄: the
pick-up distance), its **join** edges (p, a vehicle with one unpaired passenger A, when POOL accepts the
pair: pick-up distance, the pair's saving e (Eq. 5), whether A is dropped first, the pooled route's
remaining length) and one **wait** edge (keep p waiting in the current round).  These are exactly the options MB and
FL weigh (:mod:`.candidates`), so an answer in either form below is a decision the simulator can commit:

* **scores**: one number per edge, the utility (in metres) the round's assignment model maximises, as a
  strategy's utilities (Eqs. 1-4): a vacant edge's score ``-pickup_m`` and a join edge's
  ``saving_m - pickup_m`` with every wait edge at ``NO_WAIT_UTILITY_M`` are MB's round;
* **decision**: 0 or 1 per edge, at most one edge per passenger and per vehicle; a passenger with no edge
  chosen waits.  An answer that breaks that is one :class:`ParameterError` line naming the first broken
  rule, never silently repaired.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.strategies.base import RoundModel, RoundState
from rpbench.strategies.candidates import JoinOptions, VacantOptions, assignment_round, join_options, vacant_options

EDGE_KINDS = ("vacant", "join", "wait")
#: How a dispatcher answers a round: a score per edge, or a 0/1 decision per edge.
ANSWER_MODES = ("scores", "decision")
#: A chosen edge's utility in a decision: far above any other column, so the model's optimum is the decision.
CHOSEN_M = 1e7
#: An edge not chosen: far below; a passenger's wait edge is 0 unless another edge of it is chosen.
NOT_CHOSEN_M = -1e7


@dataclass(frozen=True)
class RoundEdges:
    """The round's candidate edges, in the order they are shown (passenger, then vacant, join, wait)."""

    vacant: VacantOptions
    join: JoinOptions
    kind: np.ndarray  # index into EDGE_KINDS
    passenger: np.ndarray  # position in the state's passenger arrays
    vehicle: np.ndarray  # simulator vehicle id (-1: wait)
    pickup_m: np.ndarray  # NaN for wait
    saving_m: np.ndarray  # join: e; else 0
    first_dropped: np.ndarray  # join: the passenger already aboard (A) is dropped first
    remaining_m: np.ndarray  # join: the pooled route still to drive; else NaN
    #: position of each shown edge among the model's vacant, join and wait options (in that concatenation)
    option: np.ndarray

    def __len__(self) -> int:
        return len(self.kind)


def round_edges(state: RoundState, order_rule: str = "min_feasible") -> RoundEdges:
    """The round's vacant, join and wait edges, passenger by passenger."""
    vac, join = vacant_options(state), join_options(state, order_rule)
    n_v, n_j, n_p = len(vac.p), len(join.p), state.n_passengers
    kind = np.concatenate([np.zeros(n_v, np.int8), np.ones(n_j, np.int8), np.full(n_p, 2, np.int8)])
    passenger = np.concatenate([vac.p, join.p, np.arange(n_p)])
    vehicle = np.concatenate([state.v0_vehicle[vac.v], state.v1_vehicle[join.v], np.full(n_p, -1)])
    order = np.lexsort((vehicle, kind, passenger))  # passenger, then kind, then vehicle id
    nan = np.full(n_p, np.nan)
    return RoundEdges(
        vacant=vac,
        join=join,
        kind=kind[order],
        passenger=passenger[order].astype(np.int64),
        vehicle=vehicle[order].astype(np.int64),
        pickup_m=np.concatenate([vac.pickup_m, join.pickup_m, nan])[order],
        saving_m=np.concatenate([np.zeros(n_v), join.saving_m, np.zeros(n_p)])[order],
        first_dropped=np.concatenate([np.zeros(n_v, bool), join.fofo, np.zeros(n_p, bool)])[order],
        remaining_m=np.concatenate([np.full(n_v, np.nan), join.remaining_m, nan])[order],
        option=np.arange(n_v + n_j + n_p)[order],
    )


def model_from_scores(state: RoundState, edges: RoundEdges, scores: np.ndarray, *, name: str) -> RoundModel:
    """The round's model with each edge worth its score (one finite number per edge, in the order shown)."""
    scores = _numbers(scores, len(edges), "scores")
    utility = np.empty(len(edges))
    utility[edges.option] = scores
    return _assemble(state, edges, utility, name)


def model_from_decision(state: RoundState, edges: RoundEdges, chosen: np.ndarray, *, name: str) -> RoundModel:
    """The round's model whose only optimum is ``chosen`` (0 or 1 per edge, in the order shown), checked first:
    at most one edge per passenger and per vehicle."""
    chosen = _numbers(chosen, len(edges), "decision")
    if not np.isin(chosen, (0.0, 1.0)).all():
        bad = int(np.flatnonzero(~np.isin(chosen, (0.0, 1.0)))[0])
        raise ParameterError(f"decision: edge {bad} is {chosen[bad]!r}; each edge is 0 or 1")
    picked = chosen == 1.0
    _at_most_one(edges.passenger[picked], "passenger", state.p_order)
    taken = edges.vehicle[picked & (edges.kind != 2)]
    _at_most_one(taken, "vehicle", None)
    # A passenger waits unless one of its edges is chosen: its wait edge is then the only column at 0.
    waits = np.isin(edges.passenger, edges.passenger[picked], invert=True) & (edges.kind == 2)
    utility = np.full(len(edges), NOT_CHOSEN_M)
    utility[picked] = CHOSEN_M
    utility[waits] = 0.0
    values = np.empty(len(edges))
    values[edges.option] = utility
    return _assemble(state, edges, values, name)


def _assemble(state: RoundState, edges: RoundEdges, utility: np.ndarray, name: str) -> RoundModel:
    n_v, n_j = len(edges.vacant.p), len(edges.join.p)
    return assignment_round(
        state, edges.vacant, utility[:n_v], edges.join, utility[n_v : n_v + n_j], utility[n_v + n_j :], name=name
    )


def _numbers(values: Any, n: int, what: str) -> np.ndarray:
    try:
        out = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"{what}: not a list of numbers") from None
    if len(out) != n:
        raise ParameterError(f"{what}: {len(out)} numbers for the round's {n} edges; give one per edge, in order")
    if not np.isfinite(out).all():
        bad = int(np.flatnonzero(~np.isfinite(out))[0])
        raise ParameterError(f"{what}: edge {bad} is {out[bad]!r}; each is a finite number")
    return out


def _at_most_one(ids: np.ndarray, what: str, names: np.ndarray | None) -> None:
    values, counts = np.unique(ids, return_counts=True)
    if (counts > 1).any():
        twice = int(values[counts > 1][0])
        shown = int(names[twice]) if names is not None else twice
        raise ParameterError(f"decision: {what} {shown} has {int(counts[counts > 1][0])} edges chosen; at most one")
