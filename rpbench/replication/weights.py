"""Pair utilities of one round, the authors' and rpbench's, vectorised over candidate pairs.

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
class FLParams:
    alpha: float  # waiting-priority base (authors 1.1, paper 1.01)
    response_rate: float  # r_w (authors 0.8, paper 0.75)
    double_predictions: bool
    divide_wait_by_k: bool
    patience_rounds: float = 9.0  # K / dt = 90 s / 10 s


def fl_params(authors_ledger: bool) -> FLParams:
    if authors_ledger:
        return FLParams(alpha=1.1, response_rate=0.8, double_predictions=True, divide_wait_by_k=True)
    return FLParams(alpha=1.01, response_rate=0.75, double_predictions=False, divide_wait_by_k=False)


def priority(k: np.ndarray, fresh: np.ndarray, p: FLParams) -> np.ndarray:
    """alpha^k for a passenger kept waiting k rounds; 1 for one released this round (the authors' delay = 1)."""
    return np.where(fresh, 1.0, p.alpha**k)


def balanced(e: np.ndarray, pk: np.ndarray) -> np.ndarray:
    """e^2 / (e + pk), 0 where e + pk = 0 (the authors' guard)."""
    den = e + pk
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den == 0, 0.0, e * e / np.where(den == 0, 1.0, den))


def vacant_values(
    strategy: str, authors: bool, pk: np.ndarray, solo_m: np.ndarray, e_taker: np.ndarray, prio: np.ndarray
) -> np.ndarray:
    """Model value of a vacant vehicle taking a passenger (before the offset)."""
    if strategy == "np":
        return solo_m - pk + AUTHORS_BONUS if authors else -pk
    if strategy == "mb":
        return AUTHORS_BONUS - pk if authors else -pk
    if strategy == "fl-nd":
        return e_taker - pk + AUTHORS_BONUS if authors else e_taker - pk
    if strategy == "fl":
        return balanced(e_taker, pk) * prio
    raise ValueError(strategy)


def taker_values(strategy: str, authors: bool, saving: np.ndarray, pk: np.ndarray, prio: np.ndarray) -> np.ndarray:
    """Model value of a partially occupied vehicle taking a second passenger (before the offset)."""
    if strategy in ("mb", "fl-nd"):
        return saving - pk + AUTHORS_BONUS if authors else saving - pk
    if strategy == "fl":
        return balanced(saving, pk) * prio
    raise ValueError(strategy)


def offset(strategy: str, authors: bool) -> float:
    """What the authors' dummy rows and columns add to every pair column (see the module docstring)."""
    if not authors or strategy == "fl":
        return 0.0
    return 2000.0 if strategy in ("np", "fl-nd") else 1000.0


def wait_values(strategy: str, authors: bool, e_seeker: np.ndarray, k: np.ndarray, p: FLParams) -> np.ndarray:
    """Keep-waiting value per passenger."""
    n = len(k)
    if strategy != "fl":
        return np.zeros(n) if authors else np.full(n, NEVER_WAIT)
    remaining = np.maximum(0.0, p.patience_rounds - k)
    chance = 1.0 - (1.0 - p.response_rate) ** remaining
    value = e_seeker * chance
    if p.divide_wait_by_k:
        value = value / (k + 1.0)
    # The authors return a negative predicted saving as it is (no discount).
    return np.where(e_seeker < 0, e_seeker, value)
