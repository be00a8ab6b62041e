"""NP and MB: the paper's non-pooling and myopic batch strategies (§2.2, §4).

* **NP** — passengers are matched to vacant vehicles only, utility
  ``-l^pk(v, o_p)``.
* **MB** — paper Eq. (7): ``-l^pk`` for a vacant vehicle, ``e(v_p', p) - l^pk``
  for a partially occupied one (every pair the pairing conditions accept).

Neither keeps a passenger waiting on purpose: the keep-waiting option gets
``-10^6 m`` (A13), so it is chosen only when no vehicle is feasible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rpbench.geometry import ORDER_RULES
from rpbench.model import Structure
from rpbench.options import RunOptions, option
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import (
    NO_WAIT_UTILITY_M,
    JoinOptions,
    VacantOptions,
    assignment_round,
    join_options,
    vacant_options,
)


@dataclass(frozen=True)
class PoolingOptions(RunOptions):
    """Options of a strategy that pairs passengers (§1.1)."""

    order_rule: str = option(
        "min_feasible", "drop-off order rule of a pair (docs/algorithms.md §1.1, A6)", choices=ORDER_RULES
    )


class NonPooling(Strategy[RunOptions]):
    name = "np"
    label = "NP"
    color = "tab:gray"
    structure = Structure.ASSIGNMENT
    description = "non-pooling: vacant vehicles only, minimise pick-up distance"

    def build(self, state: RoundState) -> RoundModel:
        vac = vacant_options(state)
        return assignment_round(
            state,
            vac,
            -vac.pickup_m,
            JoinOptions.empty(),
            np.zeros(0),
            np.full(state.n_passengers, NO_WAIT_UTILITY_M),
            name="np",
        )


class MyopicBatch(Strategy[PoolingOptions]):
    name = "mb"
    label = "MB"
    color = "tab:blue"
    structure = Structure.ASSIGNMENT
    Options = PoolingOptions
    description = "myopic batch matching, paper Eq. (7)"

    def build(self, state: RoundState) -> RoundModel:
        return mb_round(state, vacant_options(state), join_options(state, self.options.order_rule), name="mb")


def mb_round(state: RoundState, vac: VacantOptions, join: JoinOptions, *, name: str) -> RoundModel:
    """MB's round over the given options (Eq. 7): a vacant vehicle at ``-pickup``, a join at ``e - pickup``,
    keeping a passenger waiting at ``NO_WAIT_UTILITY_M`` (A13)."""
    return assignment_round(
        state,
        vac,
        -vac.pickup_m,
        join,
        join.saving_m - join.pickup_m,
        np.full(state.n_passengers, NO_WAIT_UTILITY_M),
        name=name,
    )
