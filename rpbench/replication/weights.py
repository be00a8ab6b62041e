"""Per-strategy rules and pair utilities of one batch, the authors' and rpbench's, vectorised over candidate pairs.

:data:`RULES` says what each strategy does differently in the authors' loop
(:class:`StrategyRules`); the engine reads it as ``self.rules.<field>``, the
way rpbench's own strategies keep their behaviour in class attributes.

The authors solve a square matrix with their own Kuhn-Munkres: supply rows
(takers, then vacant vehicles) plus one dummy row per passenger, passenger
columns plus one dummy column per vehicle.  Unmatched vehicles, unmatched
passengers and dummy-dummy cells carry constants, so the matrix is the same
optimisation as an :class:`~rpbench.model.AssignmentModel` whose pair column
is worth ``w + offset`` and whose keep-waiting column is worth ``wait``:

* MB (dummies -3000, dummy-dummy -5000): offset +1000, wait 0;
* NP and FL-no_delay (dummies -5000, dummy-dummy -8000): offset +2000, wait 0;
* FL (vehicle dummies -8000, passenger dummies = their waiting utility):
  offset 0, wait = the waiting utility.

Out-of-cell and infeasible cells (-5000 / -8000 / -1e4) can never beat the
dummies, so they are simply not columns here.  Ties between equal optima may
be broken differently from the authors' solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: rpbench's waiting utility where a strategy never prefers waiting (README: -10^6 m).
NEVER_WAIT = -1e6
AUTHORS_BONUS = 3000.0


@dataclass(frozen=True)
class StrategyRules:
    """What one strategy does differently in the authors' loop; the defaults are what no strategy changes."""

    name: str
    #: With teleport, a batch without waiting passengers or without free vehicles ends before anyone moves,
    #: and passengers are kept with a fixed 90 s patience.
    early_return: bool = False
    #: The patience floor under the authors' weights (rpbench's 30 s applies without them).
    patience_floor_s: float = 0.0
    #: Reads the per-order predicted savings of the order files (ē(p), and the seeker's for FL).
    uses_predictions: bool = False
    #: Offers waiting passengers to takers; without it a vehicle jumps to its one passenger's destination,
    #: blocked for the real pick-up and ride.
    pools: bool = True
    #: Solves one trip-packing model per batch (:mod:`rpbench.replication.rtv`) instead of the assignment.
    packs_trips: bool = False
    #: The authors' vacant-vehicle weight credits the passenger's ride: (ride - pick-up) + 3000.
    credits_ride: bool = False
    #: The balanced utility of Eq. (13), e^2 / (e + pk) x alpha^k, instead of e - pk.
    balanced_values: bool = False
    #: A keep-waiting column worth the waiting utility ē(0,p) of Eq. (10) (the intended delay).
    waiting_value: bool = False
    #: A taker is offered a passenger only if the pair's saving is not negative.
    pairs_need_saving: bool = False
    #: What the authors' dummy rows and columns add to every pair column (see the module docstring).
    authors_offset: float = 0.0
    #: With pickup_from_first_origin, a vacant vehicle's pick-up weight is measured passenger origin ->
    #: vehicle (the authors' reversed direction); without this rule, vehicle -> origin.
    reversed_vacant_pickup: bool = True
    #: The authors' ledger books only the last link of a taker's jump to its passenger's origin.
    ledger_last_link: bool = False
    #: With teleport, a vehicle assigned a first passenger moves in the same batch.
    moves_when_assigned: bool = False
    #: With teleport, an idle vehicle draws a new target every batch instead of walking back along the route
    #: of its last draw.
    idle_redraw_every_batch: bool = False


#: The rules of every strategy the authors' engine runs, in the report's order.
RULES: dict[str, StrategyRules] = {
    rules.name: rules
    for rules in (
        StrategyRules("np", pools=False, credits_ride=True, authors_offset=2000.0, reversed_vacant_pickup=False),
        StrategyRules("mb", early_return=True, authors_offset=1000.0, ledger_last_link=True),
        StrategyRules(
            "rtv", patience_floor_s=30.0, packs_trips=True, moves_when_assigned=True, idle_redraw_every_batch=True
        ),
        StrategyRules("fl-nd", early_return=True, uses_predictions=True, authors_offset=2000.0),
        StrategyRules(
            "fl",
            early_return=True,
            patience_floor_s=30.0,
            uses_predictions=True,
            balanced_values=True,
            waiting_value=True,
            pairs_need_saving=True,
        ),
    )
}


@dataclass(frozen=True)
class FLParams:
    """FL's parameters: the authors' (ledger switch on) or the paper's."""

    alpha: float  # waiting-priority base (authors 1.1, paper 1.01)
    response_rate: float  # r_w (authors 0.8, paper 0.75)
    double_predictions: bool  # the authors double both predicted savings when loading them
    divide_wait_by_k: bool
    patience_rounds: float = 9.0  # K / dt = 90 s / 10 s


def fl_params(authors_ledger: bool) -> FLParams:
    if authors_ledger:
        return FLParams(alpha=1.1, response_rate=0.8, double_predictions=True, divide_wait_by_k=True)
    return FLParams(alpha=1.01, response_rate=0.75, double_predictions=False, divide_wait_by_k=False)


def priority(k: np.ndarray, fresh: np.ndarray, p: FLParams) -> np.ndarray:
    """alpha^k for a passenger kept waiting k rounds; 1 for one released this batch (the authors' delay = 1)."""
    return np.where(fresh, 1.0, p.alpha**k)


def balanced(e: np.ndarray, pk: np.ndarray) -> np.ndarray:
    """e^2 / (e + pk) of Eq. (13), 0 where e + pk = 0 (the authors' guard)."""
    den = e + pk
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den == 0, 0.0, e * e / np.where(den == 0, 1.0, den))


def vacant_values(
    rules: StrategyRules,
    authors: bool,
    pk: np.ndarray,
    solo_m: np.ndarray,
    e_taker: np.ndarray,
    prio: np.ndarray,
) -> np.ndarray:
    """Model value of a vacant vehicle taking a passenger (before the offset); ``authors``: the authors' weights."""
    if rules.balanced_values:
        return balanced(e_taker, pk) * prio
    if authors and rules.credits_ride:
        return solo_m - pk + AUTHORS_BONUS
    if rules.uses_predictions:  # Eq. (15): ē(p) - pk
        return e_taker - pk + AUTHORS_BONUS if authors else e_taker - pk
    return AUTHORS_BONUS - pk if authors else -pk  # Eq. (7): -pk


def taker_values(
    rules: StrategyRules, authors: bool, saving: np.ndarray, pk: np.ndarray, prio: np.ndarray
) -> np.ndarray:
    """Model value of a partially occupied vehicle taking a second passenger (before the offset)."""
    if rules.balanced_values:
        return balanced(saving, pk) * prio
    return saving - pk + AUTHORS_BONUS if authors else saving - pk  # Eqs. (7), (15): e - pk


def offset(rules: StrategyRules, authors: bool) -> float:
    """What the authors' dummy rows and columns add to every pair column (see the module docstring)."""
    return rules.authors_offset if authors else 0.0


def wait_values(rules: StrategyRules, authors: bool, e_seeker: np.ndarray, k: np.ndarray, p: FLParams) -> np.ndarray:
    """Keep-waiting value per passenger: FL's ē(0,p) of Eq. (10), else never preferred to a match."""
    n = len(k)
    if not rules.waiting_value:
        return np.zeros(n) if authors else np.full(n, NEVER_WAIT)
    remaining = np.maximum(0.0, p.patience_rounds - k)
    chance = 1.0 - (1.0 - p.response_rate) ** remaining
    value = e_seeker * chance
    if p.divide_wait_by_k:
        value = value / (k + 1.0)
    # The authors return a negative predicted saving as it is (no discount).
    return np.where(e_seeker < 0, e_seeker, value)
