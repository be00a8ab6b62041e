"""Compiled checks (numba) of the models a simulation round builds and solves, many times a second.

A round's model has tens to thousands of columns; its validation and the check of its solution were
each a few dozen numpy passes whose call overhead, not their work, dominated a round.  These kernels
decide the same questions in one pass each; the models' Python checks still word every error, and
run whenever a kernel finds something wrong (or cannot decide, such as values whose sum approaches
the float64 limit).  Imported on first use, so that reading a model needs no compiler.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: The kernel leaves value sums above this to the Python check (which compares with 2**53 exactly).
_SAFE_TOTAL = float(2**52)


@njit(cache=True, nogil=True)
def assignment_valid(
    n_passengers: int, n_vehicles: int, col_passenger: np.ndarray, col_vehicle: np.ndarray, values: np.ndarray
) -> bool:  # pragma: no cover - compiled
    """Whether an assignment model passes every check of ``AssignmentModel._validate`` (unit aside).

    Values finite and whole with a sum of magnitudes far below 2**53; passengers in
    ``[0, n_passengers)``, vehicles in ``[-1, n_vehicles)``; no (passenger, vehicle) twice; every
    passenger with a column.  False sends the caller to the Python checks, which say what is wrong.
    """
    n = len(values)
    if n_passengers < 0 or n_vehicles < 0 or len(col_passenger) != n or len(col_vehicle) != n:
        return False
    total = 0.0
    has_option = np.zeros(n_passengers, np.bool_)
    key = np.empty(n, np.int64)
    for c in range(n):
        v = values[c]
        if not math.isfinite(v) or v != math.floor(v):
            return False
        total += abs(v)
        p, w = col_passenger[c], col_vehicle[c]
        if p < 0 or p >= n_passengers or w < -1 or w >= n_vehicles:
            return False
        has_option[p] = True
        key[c] = np.int64(p) * (n_vehicles + 1) + (w + 1)
    if not total <= _SAFE_TOTAL:
        return False
    for p in range(n_passengers):
        if not has_option[p]:
            return False
    key.sort()
    for c in range(1, n):  # noqa: SIM110 (numba compiles loops, not generators)
        if key[c] == key[c - 1]:
            return False
    return True


@njit(cache=True, nogil=True)
def cover(
    start: np.ndarray, rows: np.ndarray, exact: np.ndarray, chosen: np.ndarray
) -> tuple[int, int, int, int, int]:  # pragma: no cover - compiled
    """How the columns ``chosen`` cover the rows (CSC ``start``, ``rows``): a tuple of

    * 1 when an index lies outside the columns (nothing else is then looked at), else 0;
    * 1 when a column is chosen twice, else 0;
    * the first row covered more than once (-1: none) and how often it is covered;
    * the first "exactly once" row (``exact``) left uncovered (-1: none).
    """
    n_cols = len(start) - 1
    for c in chosen:
        if c < 0 or c >= n_cols:
            return 1, 0, -1, 0, -1
    twice = 0
    seen = np.zeros(n_cols, np.bool_)
    counts = np.zeros(len(exact), np.int64)
    for c in chosen:
        if seen[c]:
            twice = 1
        seen[c] = True
        for e in range(start[c], start[c + 1]):
            counts[rows[e]] += 1
    over, times, under = -1, 0, -1
    for r in range(len(exact)):
        if over < 0 and counts[r] > 1:
            over, times = r, counts[r]
        if under < 0 and exact[r] and counts[r] == 0:
            under = r
    return 0, twice, over, times, under


def load_model_kernels() -> None:
    """Load (or compile) the kernels now: the first call of each costs a one-off load of its machine code."""
    assignment_valid(1, 1, np.zeros(1, np.int32), np.zeros(1, np.int32), np.zeros(1))
    cover(np.array([0, 1], np.int64), np.zeros(1, np.int32), np.ones(1, np.bool_), np.zeros(1, np.int64))
