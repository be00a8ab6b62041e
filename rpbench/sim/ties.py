"""Solver-independent choice among tied optima.

Different exact solvers may return different optimal solutions of the same
round model when optima tie (two vacant vehicles waiting at the same node,
two passengers at the same origin...).  Committing whichever one a solver
happens to return would make trajectories — and KPI tables — depend on the
solver.  rpbench therefore post-processes every *optimal* solution with
value-neutral exchanges towards lower column indices (models list their
columns in a deterministic order, e.g. by passenger then vehicle id):

1. *replace*: a chosen column is swapped for an unchosen column of the same
   value that covers the same "exactly one" rows and otherwise only free
   rows, if that column comes earlier;
2. *swap resources*: two chosen columns exchange their vehicles when both
   exchanged columns exist, the total value is unchanged and the smallest
   column index decreases.

Each move strictly decreases the sorted tuple of chosen column indices, so
the repair terminates, and every move keeps the objective exactly (values
are integers).  It resolves symmetric ties (interchangeable vehicles or
passengers) completely; ties needing longer exchange cycles are not
canonicalised (with millimetre-resolution road distances they are
practically absent; the cross-solver test in tests/test_sim.py checks it).
Solutions that are not proven optimal are left untouched.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rpbench.model import AssignmentModel, Model, Solution, Status, TripPackingModel, make_solution


def canonicalize(model: Model, solution: Solution) -> tuple[Solution, int]:
    """Return the canonical optimum reachable from ``solution`` and the number of moves made."""
    # A proven-unique optimum has no value-neutral move (each would give a second optimum).
    if solution.status != Status.OPTIMAL or len(solution.chosen) == 0 or solution.unique:
        return solution, 0
    items: np.ndarray  # per column, the orders it serves: one row, or two for a trip
    # The model's own int32 columns go to the kernel as they are (no int64 copies: it widens as it reads).
    if isinstance(model, AssignmentModel):
        resource = model.col_vehicle
        items = model.col_passenger.reshape(1, -1)
    elif isinstance(model, TripPackingModel):
        resource = model.col_vehicle
        items = np.stack((model.col_request1, model.col_request2))
    else:
        return solution, 0
    chosen, moves = _repair(model, solution.chosen, resource, items)
    if moves == 0:
        return solution, 0
    fixed = make_solution(
        model,
        chosen,
        solution.status,
        solution.backend,
        bound=solution.bound,
        gap=solution.gap,
        build_s=solution.build_s,
        solve_s=solution.solve_s,
        extract_s=solution.extract_s,
        message=solution.message,
    )
    if fixed.objective != solution.objective:  # pragma: no cover - moves are value-neutral by construction
        raise AssertionError("tie canonicalisation changed the objective")
    return fixed, moves


def _repair(model, chosen: np.ndarray, resource: np.ndarray, items: np.ndarray):
    """The moves of the module docstring until none applies: the chosen columns (sorted) and the moves made.

    ``items``: per column, the orders it serves (one row of the table per order slot: one for an
    assignment, two for a trip), ``-1`` where a slot is empty.
    """
    start, rows = model.column_rows()
    out = np.sort(chosen.astype(np.int64, copy=False))  # a new array: the kernel changes it in place
    moves = _repair_kernel(
        np.ascontiguousarray(model.values, dtype=np.float64),
        start.astype(np.int64, copy=False),
        rows,
        model.row_exact(),
        resource,
        items,
        out,
    )
    return out, moves


@njit(cache=True, nogil=True)
def _repair_kernel(values, start, rows, exact, resource, items, chosen) -> int:  # pragma: no cover - compiled
    """Apply value-neutral moves to ``chosen`` (sorted, changed in place) until none applies; the number made.

    Each pass tries, in order: (1) the first *replace*: over the chosen columns in index order, the
    earliest column with the same value and the same first "exactly one" row (its group), covering no
    row another chosen column covers and every "exactly one" row of the column it replaces; (2) the
    first *swap* of two chosen columns' resources, over their pairs i < j in row-major order, whose
    exchanged columns exist, keep the total value and lower the smaller index.  A column's items and
    resource form an integer key (mixed radix) found by binary search among the sorted keys.
    """
    n = len(values)
    n_rows = len(exact)
    # the group of each column: its first exact row (-1: none), listed by group in index order
    group = np.full(n, -1, np.int64)
    for c in range(n):
        for e in range(start[c], start[c + 1]):
            if exact[rows[e]]:
                group[c] = rows[e]
                break
    g_start = np.zeros(n_rows + 2, np.int64)
    for c in range(n):
        g_start[group[c] + 2] += 1
    for g in range(1, n_rows + 2):
        g_start[g] += g_start[g - 1]
    members = np.empty(n, np.int64)
    fill = g_start[:-1].copy()
    for c in range(n):
        members[fill[group[c] + 1]] = c
        fill[group[c] + 1] += 1
    # key of (items, resource) per column, and the key with the resource zeroed
    key = np.zeros(n, np.int64)
    for a in range(items.shape[0] + 1):
        col = items[a] if a < items.shape[0] else resource
        top = 0
        for c in range(n):
            top = max(top, col[c])
        for c in range(n):
            key[c] = key[c] * (top + 2) + (col[c] + 1)
    key_order = np.argsort(key, kind="mergesort")
    sorted_keys = key[key_order]
    used = np.zeros(n_rows, np.bool_)
    m = len(chosen)
    moves = 0
    while True:
        chosen.sort()
        # (1) replace
        used[:] = False
        for i in range(m):
            for e in range(start[chosen[i]], start[chosen[i] + 1]):
                used[rows[e]] = True
        replaced = False
        for i in range(m):
            c = chosen[i]
            g = group[c] + 1
            for e in range(start[c], start[c + 1]):
                used[rows[e]] = False
            for q in range(g_start[g], g_start[g + 1]):
                c2 = members[q]
                if c2 >= c:
                    break
                if values[c2] != values[c]:
                    continue
                ok = True
                for e in range(start[c2], start[c2 + 1]):
                    if used[rows[e]]:
                        ok = False
                        break
                if ok:  # every exact row of c is a row of c2
                    for e in range(start[c], start[c + 1]):
                        r = rows[e]
                        if exact[r]:
                            found = False
                            for f in range(start[c2], start[c2 + 1]):
                                if rows[f] == r:
                                    found = True
                                    break
                            if not found:
                                ok = False
                                break
                if ok:
                    chosen[i] = c2
                    replaced = True
                    break
            if replaced:
                break
            for e in range(start[c], start[c + 1]):
                used[rows[e]] = True
        if replaced:
            moves += 1
            continue
        # (2) swap resources
        swapped = False
        for i in range(m):
            cx = chosen[i]
            rx = resource[cx]
            if rx < 0:
                continue
            for j in range(i + 1, m):
                cy = chosen[j]
                ry = resource[cy]
                if ry < 0 or rx == ry:
                    continue
                nx = _column_with(sorted_keys, key_order, key[cx] - (rx + 1) + ry + 1)
                ny = _column_with(sorted_keys, key_order, key[cy] - (ry + 1) + rx + 1)
                if nx < 0 or ny < 0 or values[nx] + values[ny] != values[cx] + values[cy]:
                    continue
                if min(nx, ny) < min(cx, cy):
                    chosen[i], chosen[j] = nx, ny
                    swapped = True
                    break
            if swapped:
                break
        if not swapped:
            break
        moves += 1
    chosen.sort()
    return moves


@njit(cache=True, nogil=True, inline="always")
def _column_with(sorted_keys, key_order, q) -> int:  # pragma: no cover - compiled
    """The column whose key is ``q``, or -1."""
    pos = min(np.searchsorted(sorted_keys, q), len(sorted_keys) - 1)
    return key_order[pos] if sorted_keys[pos] == q else -1


def load_tie_kernels() -> None:
    """Load (or compile) the kernel now: its first call costs a one-off load of its machine code."""
    model = AssignmentModel(1, 1, [0, 0], [0, -1], [0.0, 0.0])
    for m in (model, model.frozen()):  # a round passes a frozen model: read-only arrays, machine code of their own
        _repair(m, np.zeros(1, np.int64), m.col_vehicle, m.col_passenger.reshape(1, -1))
        _repair(m, np.zeros(1, np.int64), m.col_vehicle, np.stack((m.col_passenger,)))  # a trip's stacked orders
