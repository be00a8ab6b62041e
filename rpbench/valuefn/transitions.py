"""A run's vehicle transitions: from one vacant state to the next, with the saving earned between.

A vehicle's state is observed at every batch round in which it is vacant (a V0 row of the round).
Between two consecutive observations at ``t_i`` and ``t_j`` it may have served passengers; the reward
of the transition is the realised saving ``l_A + l_B - L`` (Eq. 5) of every pair it delivered in
``(t_i, t_j]``, each discounted to ``t_i`` by ``γ^((t_done - t_i) / bin_s)``, and the next state's
value is discounted by ``γ^((t_j - t_i) / bin_s)``.  A vehicle's last observation leads to the
terminal state (value 0) with the savings of the pairs it delivered afterwards.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from rpbench.valuefn.cells import Grid


@dataclass(frozen=True, eq=False)
class Observations:
    """Vacant-vehicle observations of a run: one row per (round, V0 vehicle)."""

    t_s: np.ndarray
    vehicle: np.ndarray
    node: np.ndarray

    @classmethod
    def of_rounds(cls, rounds: list[tuple[float, np.ndarray, np.ndarray]]) -> Observations:
        """From ``(t, v0_vehicle, v0_node)`` of each round, in round order."""
        if not rounds:
            empty = np.zeros(0, np.int64)
            return cls(np.zeros(0), empty, empty)
        t = np.concatenate([np.full(len(v), t, dtype=np.float64) for t, v, _ in rounds])
        return cls(
            t,
            np.concatenate([np.asarray(v, np.int64) for _, v, _ in rounds]),
            np.concatenate([np.asarray(n, np.int64) for _, _, n in rounds]),
        )


@dataclass(frozen=True, eq=False)
class Transitions:
    """Arrays of one row per transition: ``state`` -> ``next_state`` (-1: terminal), ``reward_m`` (already
    discounted to the transition's start), ``gamma`` (the discount of the next state's value) and the
    start time ``t_s`` (the order online TD(0) visits them in)."""

    state: np.ndarray
    next_state: np.ndarray
    reward_m: np.ndarray
    gamma: np.ndarray
    t_s: np.ndarray

    def __len__(self) -> int:
        return len(self.state)

    @classmethod
    def concat(cls, parts: list[Transitions]) -> Transitions:
        return cls(
            *(
                np.concatenate([getattr(p, f) for p in parts])
                for f in ("state", "next_state", "reward_m", "gamma", "t_s")
            )
        )


def transitions_of_run(obs: Observations, pairs: pd.DataFrame, grid: Grid, discount: float) -> Transitions:
    """The transitions of one run (``pairs``: :func:`rpbench.results.metrics.pair_savings` of its passengers).

    ``discount`` is γ per ``grid.bin_s`` seconds.
    """
    order = np.lexsort((obs.t_s, obs.vehicle))
    t, vehicle, node = obs.t_s[order], obs.vehicle[order], obs.node[order]
    n = len(t)
    state = grid.state(node, t)
    last = np.r_[vehicle[1:] != vehicle[:-1], True] if n else np.zeros(0, bool)
    nxt = np.minimum(np.arange(n) + 1, max(n - 1, 0))
    next_state = np.where(last, -1, state[nxt] if n else state)
    gamma = np.where(last, 0.0, discount ** ((t[nxt] - t) / grid.bin_s) if n else 0.0)
    reward = np.zeros(n)
    if len(pairs) and n:
        # each pair belongs to its vehicle's last observation strictly before the pair was delivered
        span = float(max(t.max(), pairs["done_s"].max())) + 1.0
        key = vehicle * span + t
        pv = pairs["vehicle"].to_numpy(np.int64)
        done = pairs["done_s"].to_numpy(np.float64)
        at = np.searchsorted(key, pv * span + done, side="left") - 1
        ok = (at >= 0) & (vehicle[np.maximum(at, 0)] == pv)
        if not ok.all():  # a pair its vehicle delivered without ever having been vacant in a round
            bad = int(np.flatnonzero(~ok)[0])
            raise ValueError(f"vehicle {int(pv[bad])} delivered a pair at {done[bad]:g} s before any vacant round")
        np.add.at(reward, at, pairs["saving_m"].to_numpy(np.float64) * discount ** ((done - t[at]) / grid.bin_s))
    return Transitions(state, next_state.astype(np.int64), reward, gamma, t)
