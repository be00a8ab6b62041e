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


@njit(cache=True, nogil=True)
def assignment_column_rows(
    n_passengers: int, col_passenger: np.ndarray, col_vehicle: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """An assignment model's rows per column as CSC ``(start, rows)``: each column's passenger row, then,
    unless it keeps the passenger waiting (vehicle -1), its vehicle's row ``n_passengers + vehicle``."""
    n = len(col_passenger)
    start = np.empty(n + 1, np.int64)
    start[0] = 0
    for c in range(n):
        start[c + 1] = start[c] + (2 if col_vehicle[c] >= 0 else 1)
    rows = np.empty(start[n], np.int32)
    for c in range(n):
        rows[start[c]] = col_passenger[c]
        if col_vehicle[c] >= 0:
            rows[start[c] + 1] = n_passengers + col_vehicle[c]
    return start, rows


@njit(cache=True, nogil=True)
def first_outside_int32(arr: np.ndarray) -> int:  # pragma: no cover - compiled
    """The first entry of an integer array outside int32's range (-1: none)."""
    lo, hi = np.iinfo(np.int32).min, np.iinfo(np.int32).max
    for i in range(len(arr)):
        if arr[i] < lo or arr[i] > hi:
            return i
    return -1


@njit(cache=True, nogil=True)
def integral_support(x: np.ndarray) -> tuple[float, int, np.ndarray]:  # pragma: no cover - compiled
    """A solver's 0/1 values read in one pass: the largest distance to an integer ``max |x - round(x)|``
    (0 for no values, NaN when some distance is NaN) and the first entry attaining it (as ``np.max`` and
    ``np.argmax`` give them), and the entries ``> 0.5`` in increasing order (as ``np.flatnonzero(x > 0.5)``)."""
    n = len(x)
    worst = 0.0
    at = 0
    count = 0
    for i in range(n):
        off = abs(x[i] - np.round(x[i]))
        if worst == worst and (off != off or off > worst):  # the first NaN stays, as in np.max
            worst, at = off, i
        if x[i] > 0.5:
            count += 1
    chosen = np.empty(count, np.int64)
    k = 0
    for i in range(n):
        if x[i] > 0.5:
            chosen[k] = i
            k += 1
    return worst, at, chosen


@njit(cache=True, nogil=True)
def strictly_increasing(a: np.ndarray) -> bool:  # pragma: no cover - compiled
    """Whether every entry is larger than the one before it (sorted, no repeats)."""
    for i in range(1, len(a)):  # noqa: SIM110 (numba compiles loops, not generators)
        if not a[i] > a[i - 1]:
            return False
    return True


def load_model_kernels() -> None:
    """Load (or compile) the kernels now: the first call of each costs a one-off load of its machine code."""
    assignment_valid(1, 1, np.zeros(1, np.int32), np.zeros(1, np.int32), np.zeros(1))
    cover(np.array([0, 1], np.int64), np.zeros(1, np.int32), np.ones(1, np.bool_), np.zeros(1, np.int64))
    assignment_column_rows(1, np.zeros(1, np.int32), np.zeros(1, np.int32))
    first_outside_int32(np.zeros(1, np.int64))
    integral_support(np.zeros(1))
    strictly_increasing(np.zeros(1, np.int64))
    # as a round calls them on a frozen model (read-only arrays: machine code of its own)
    p, v, values = read_only(np.zeros(1, np.int32)), read_only(np.zeros(1, np.int32)), read_only(np.zeros(1))
    assignment_valid(1, 1, p, v, values)
    assignment_column_rows(1, p, v)
    start, rows, exact = read_only(np.array([0, 1], np.int64)), p, read_only(np.ones(1, np.bool_))
    chosen = read_only(np.zeros(1, np.int64))
    cover(start, rows, exact, chosen)
    strictly_increasing(chosen)


def read_only(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only, for warming up a kernel as a run calls it: numba compiles one machine code per
    writability of the arrays, and a run's models and distance tables are read-only."""
    a.setflags(write=False)
    return a
