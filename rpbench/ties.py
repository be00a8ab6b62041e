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

from .model import AssignmentModel, Solution, Status, TripPackingModel, make_solution


def canonicalize(model, solution: Solution) -> tuple[Solution, int]:
    """Return the canonical optimum reachable from ``solution`` and the number of moves made."""
    if solution.status != Status.OPTIMAL or len(solution.chosen) == 0:
        return solution, 0
    if isinstance(model, AssignmentModel):
        resource = model.col_vehicle.astype(np.int64)
        items = (model.col_passenger.astype(np.int64),)
    elif isinstance(model, TripPackingModel):
        resource = model.col_vehicle.astype(np.int64)
        items = (model.col_request1.astype(np.int64), model.col_request2.astype(np.int64))
    else:
        return solution, 0
    chosen, moves = _repair(model, solution.chosen.astype(np.int64), resource, items)
    if moves == 0:
        return solution, 0
    fixed = make_solution(model, chosen, solution.status, solution.backend, bound=solution.bound, gap=solution.gap,
                          build_s=solution.build_s, solve_s=solution.solve_s, extract_s=solution.extract_s,
                          message=solution.message)
    if fixed.objective != solution.objective:  # pragma: no cover - moves are value-neutral by construction
        raise AssertionError("tie canonicalisation changed the objective")
    return fixed, moves


def _repair(model, chosen: np.ndarray, resource: np.ndarray, items: tuple[np.ndarray, ...]):
    values = model.values
    start, rows = model.column_rows()
    exact = model.row_exact()

    def rows_of(c: int) -> np.ndarray:
        return rows[start[c]:start[c + 1]]

    # Integer key of (items, resource) per column, for "does the exchanged column exist?"
    key = np.zeros(model.n_cols, dtype=np.int64)
    for a in items + (resource,):
        key = key * (int(a.max(initial=0)) + 2) + (a + 1)
    key_order = np.argsort(key, kind="stable")
    sorted_keys = key[key_order]
    item_key = key - (resource + 1)                    # the same key with the resource zeroed

    def column_with(item_part: int, res: int) -> int | None:
        q = item_part + res + 1
        pos = int(np.searchsorted(sorted_keys, q))
        return int(key_order[pos]) if pos < len(sorted_keys) and sorted_keys[pos] == q else None

    moves = 0
    changed = True
    while changed:
        changed = False
        chosen = np.sort(chosen)
        used = np.zeros(model.n_rows, dtype=bool)
        for c in chosen:
            used[rows_of(c)] = True
        # 1. replace a chosen column by an earlier one of equal value
        for pos, c in enumerate(chosen):
            mine = rows_of(c)
            used[mine] = False
            need = mine[exact[mine]]
            for c2 in np.flatnonzero(values[:c] == values[c]):
                r2 = rows_of(c2)
                if used[r2].any() or not np.isin(need, r2).all():
                    continue
                chosen[pos], mine = c2, r2
                moves += 1
                changed = True
                break
            used[mine] = True
            if changed:
                break
        if changed:
            continue
        # 2. swap the resources of two chosen columns
        for x in range(len(chosen)):
            for y in range(x + 1, len(chosen)):
                rx, ry = int(resource[chosen[x]]), int(resource[chosen[y]])
                if rx < 0 or ry < 0 or rx == ry:
                    continue
                cx = column_with(int(item_key[chosen[x]]), ry)
                cy = column_with(int(item_key[chosen[y]]), rx)
                if cx is None or cy is None:
                    continue
                if values[cx] + values[cy] != values[chosen[x]] + values[chosen[y]]:
                    continue
                if min(cx, cy) >= min(chosen[x], chosen[y]):
                    continue
                chosen[x], chosen[y] = cx, cy
                moves += 1
                changed = True
                break
            if changed:
                break
    return np.sort(chosen), moves
