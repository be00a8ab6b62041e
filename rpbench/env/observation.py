"""What the agent sees of a round and how its action becomes the round's model.

A round's candidate edges (:mod:`rpbench.strategies.edges`: per waiting passenger its vacant, join and
wait edges) are shown padded to ``max_edges`` rows:

* ``edges`` (``max_edges`` x :data:`EDGE_FEATURES`, float32): the edge's kind as three 0/1 columns, its
  pick-up distance, the pair's planned saving e (Eq. 5), whether the passenger already aboard is dropped
  first, the pooled route still to drive (km), and the passenger's solo distance (km), minutes waited and
  rounds waited (k_p, A10);
* ``passenger`` and ``vehicle`` (int64): the edge's passenger (its position among the round's waiting
  passengers) and vehicle (simulator id; -1 for a wait edge), -1 in padding rows;
* ``mask`` (0/1): which rows are edges;
* ``clock`` (float32): the round's time as a share of the scenario's horizon, and the numbers of waiting
  passengers, vacant vehicles and vehicles with one passenger.

A round with more edges than ``max_edges`` is shown passenger by passenger (they come in request order)
until the next passenger's edges would not fit; the passengers not shown wait in the current round (``held`` in the
step's info).  A passenger whose edges alone do not fit is an error naming ``max_edges``.

The action is one row per edge, padding ignored: a score (mode ``scores``, the utility in metres the
round's assignment model maximises, Eqs. 1-4) or a 0/1 decision (mode ``decision``), as the language-neutral
protocol's answers (docs/protocol.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.strategies.base import RoundModel, RoundState
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M
from rpbench.strategies.edges import NOT_CHOSEN_M, RoundEdges, model_from_decision, model_from_scores

EDGE_FEATURES = (
    "vacant",
    "join",
    "wait",
    "pickup_km",
    "saving_km",
    "first_dropped",
    "remaining_km",
    "solo_km",
    "waited_min",
    "rounds_waited",
)
CLOCK_FEATURES = ("time_share", "waiting", "vacant_vehicles", "one_passenger_vehicles")
#: A score's bounds: the size of MB's keep-waiting utility, far beyond any pick-up or saving in metres.
SCORE_BOUND_M = -NO_WAIT_UTILITY_M


def observation_space(max_edges: int) -> gym.spaces.Dict:
    big = np.iinfo(np.int64).max
    return gym.spaces.Dict(
        {
            "edges": gym.spaces.Box(-np.inf, np.inf, (max_edges, len(EDGE_FEATURES)), np.float32),
            "passenger": gym.spaces.Box(-1, max_edges - 1, (max_edges,), np.int64),
            "vehicle": gym.spaces.Box(-1, big, (max_edges,), np.int64),
            "mask": gym.spaces.MultiBinary(max_edges),
            "clock": gym.spaces.Box(0.0, np.inf, (len(CLOCK_FEATURES),), np.float32),
        }
    )


def action_space(mode: str, max_edges: int) -> gym.spaces.Space:
    if mode == "scores":
        return gym.spaces.Box(-SCORE_BOUND_M, SCORE_BOUND_M, (max_edges,), np.float64)
    return gym.spaces.MultiBinary(max_edges)


@dataclass(frozen=True)
class ShownRound:
    """A round as shown: its state and edges, how many of the edges are shown (a prefix) and how many
    waiting passengers were held back."""

    state: RoundState
    edges: RoundEdges
    shown: int
    held: int


def shown_round(state: RoundState, edges: RoundEdges, max_edges: int) -> ShownRound:
    """The longest prefix of whole passengers whose edges fit in ``max_edges`` rows."""
    n = len(edges)
    if n <= max_edges:
        return ShownRound(state, edges, n, 0)
    # edges.passenger is sorted: a passenger's edges end where the next passenger's start
    ends = np.flatnonzero(np.diff(edges.passenger)) + 1
    fitting = ends[ends <= max_edges]
    if not len(fitting):
        first = int(np.searchsorted(edges.passenger, edges.passenger[0], side="right"))
        raise ParameterError(
            f"round t={state.t_s:g} s: passenger {int(state.p_order[0])} alone has {first} edges, more than "
            f"max_edges={max_edges}; raise max_edges"
        )
    shown = int(fitting[-1])
    return ShownRound(state, edges, shown, state.n_passengers - int(edges.passenger[shown]))


def observe(r: ShownRound | None, max_edges: int, horizon_s: float) -> dict[str, np.ndarray]:
    """The observation of a shown round (``None``: the empty one after the episode's end)."""
    obs: dict[str, np.ndarray] = {
        "edges": np.zeros((max_edges, len(EDGE_FEATURES)), np.float32),
        "passenger": np.full(max_edges, -1, np.int64),
        "vehicle": np.full(max_edges, -1, np.int64),
        "mask": np.zeros(max_edges, np.int8),
        "clock": np.zeros(len(CLOCK_FEATURES), np.float32),
    }
    if r is None:
        return obs
    e, s, n = r.edges, r.state, r.shown
    p = e.passenger[:n]
    features = np.column_stack(
        [
            e.kind[:n] == 0,
            e.kind[:n] == 1,
            e.kind[:n] == 2,
            np.nan_to_num(e.pickup_m[:n]) / 1000.0,
            e.saving_m[:n] / 1000.0,
            e.first_dropped[:n],
            np.nan_to_num(e.remaining_m[:n]) / 1000.0,
            s.p_solo_m[p] / 1000.0,
            (s.t_s - s.p_request_s[p]) / 60.0,
            s.p_rounds_waited[p],
        ]
    )
    obs["edges"][:n] = features
    obs["passenger"][:n] = p
    obs["vehicle"][:n] = e.vehicle[:n]
    obs["mask"][:n] = 1
    obs["clock"][:] = (s.t_s / horizon_s if horizon_s > 0 else 0.0, s.n_passengers, s.n_v0, s.n_v1)
    return obs


def round_model(r: ShownRound, mode: str, action: np.ndarray, max_edges: int) -> RoundModel:
    """The round's model from the action's first ``shown`` rows; the held passengers wait."""
    try:
        values = np.asarray(action, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"action: not an array of {max_edges} numbers") from None
    if len(values) != max_edges:
        raise ParameterError(f"action: {len(values)} numbers; the action space has {max_edges} (one per edge row)")
    e, n = r.edges, r.shown
    if mode == "scores":
        scores = np.where(e.kind == 2, 0.0, NOT_CHOSEN_M)  # held: waiting is their only column worth taking
        scores[:n] = values[:n]
        return model_from_scores(r.state, e, scores, name="agent")
    chosen = np.zeros(len(e))
    chosen[:n] = values[:n]
    return model_from_decision(r.state, e, chosen, name="agent")
