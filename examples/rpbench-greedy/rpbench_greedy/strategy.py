"""A pick-up-penalised batch strategy: MB with the pick-up distance weighed ``pickup_weight`` times.

MB (paper Eq. 7) values a vacant vehicle at ``-pick-up`` and a partially
occupied one at ``saving - pick-up``.  This strategy multiplies the pick-up
by ``pickup_weight``: at 1 it is MB; above 1 it leans towards the nearest
vehicle (a large weight gives greedy nearest-vehicle dispatch that still
pools when the saving pays for the pick-up).  ``max_pickup_m`` optionally
tightens the scenario's pick-up radius R̄.

Everything rpbench needs is a class attribute (name, label, colour, the
model's structure, a description, the typed options); :meth:`build` reuses
rpbench's enumeration of the feasible options and its model assembly.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.options import RunOptions, option
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M, assignment_round, join_options, vacant_options

#: Largest pick-up weight: utilities (in mm) must stay exact in float64 sums.
MAX_WEIGHT = 100.0


@dataclass(frozen=True)
class GreedyOptions(RunOptions):
    """``--opt greedy.pickup_weight=3 --opt greedy.max_pickup_m=1500``"""

    pickup_weight: float = option(2.0, "factor on the pick-up distance in every utility (1 = MB)")
    max_pickup_m: float | None = option(None, "pick-up radius tighter than the scenario's R̄ (none = R̄)")

    def __post_init__(self) -> None:
        if not 0.0 <= self.pickup_weight <= MAX_WEIGHT:
            raise ParameterError(
                f"greedy: option pickup_weight = {self.pickup_weight!r} must lie in [0, {MAX_WEIGHT:g}]"
            )
        if self.max_pickup_m is not None and self.max_pickup_m <= 0:
            raise ParameterError(f"greedy: option max_pickup_m = {self.max_pickup_m!r} must be > 0")


class GreedyPickup(Strategy):
    name = "greedy"
    label = "Greedy"
    color = "tab:olive"
    structure = Structure.ASSIGNMENT
    Options = GreedyOptions
    description = "MB with the pick-up distance weighed pickup_weight times (leans to the nearest vehicle)"

    def build(self, state: RoundState) -> RoundModel:
        w, limit = self.options.pickup_weight, self.options.max_pickup_m
        vac, join = vacant_options(state), join_options(state)
        if limit is not None:
            vac, join = _within(vac, limit), _within(join, limit)
        # Waiting must stay worse than any feasible vehicle, however heavily pick-ups weigh (as in MB, A13).
        wait = np.full(state.n_passengers, NO_WAIT_UTILITY_M * max(1.0, w))
        return assignment_round(
            state, vac, -w * vac.pickup_m, join, join.saving_m - w * join.pickup_m, wait, name="greedy"
        )


def _within(options, limit_m: float):
    """The vacant or join options whose pick-up distance is at most ``limit_m``."""
    keep = options.pickup_m <= limit_m
    return type(options)(**{f.name: getattr(options, f.name)[keep] for f in dataclasses.fields(options)})
