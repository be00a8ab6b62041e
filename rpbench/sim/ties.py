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

import functools

import numpy as np

from rpbench.model import AssignmentModel, Model, Solution, Status, TripPackingModel, make_solution


def canonicalize(model: Model, solution: Solution) -> tuple[Solution, int]:
    """Return the canonical optimum reachable from ``solution`` and the number of moves made."""
    # A proven-unique optimum has no value-neutral move (each would give a second optimum).
    if solution.status != Status.OPTIMAL or len(solution.chosen) == 0 or solution.unique:
        return solution, 0
    items: tuple[np.ndarray, ...]  # per column, the orders it serves: one array, or two for a trip
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


def _repair(model, chosen: np.ndarray, resource: np.ndarray, items: tuple[np.ndarray, ...]):
    values = model.values
    start, rows = model.column_rows()
    exact = model.row_exact()
    n = model.n_cols

    def rows_of(c: int) -> np.ndarray:
        return rows[start[c] : start[c + 1]]

    # Replacement candidates share the value and the "exactly one" rows of the column they replace
    # (for an assignment: the same passenger), so waiting options of other passengers never qualify.
    exact_key = np.full(n, -1, dtype=np.int64)
    if exact.any():
        col_of_entry = np.repeat(np.arange(n), np.diff(start))
        is_exact = exact[rows]
        exact_key[col_of_entry[is_exact][::-1]] = rows[is_exact][::-1]
    # Smallest column index with the same (exact rows, value): a column can only be replaced by an
    # earlier peer, so most rounds are settled by one vectorised test.
    order = np.lexsort((np.arange(n), values, exact_key))
    new_group = np.r_[True, (np.diff(exact_key[order]) != 0) | (np.diff(values[order]) != 0)]
    first_of_group = np.empty(n, dtype=np.int64)
    first_of_group[order] = order[np.flatnonzero(new_group)[np.cumsum(new_group) - 1]]

    # Integer key of (items, resource) per column, for "does the exchanged column exist?"
    key = np.zeros(n, dtype=np.int64)
    for a in items + (resource,):
        key = key * (int(a.max(initial=0)) + 2) + (a + 1)
    key_order = np.argsort(key, kind="stable")
    sorted_keys = key[key_order]
    item_key = key - (resource + 1)  # the same key with the resource zeroed

    def columns_with(item_part: np.ndarray, res: np.ndarray) -> np.ndarray:
        q = item_part + res + 1
        pos = np.minimum(np.searchsorted(sorted_keys, q), n - 1)
        return np.where(sorted_keys[pos] == q, key_order[pos], -1)

    moves = 0
    while True:
        chosen = np.sort(chosen)
        if (first_of_group[chosen] < chosen).any() and _replace_once(
            chosen, values, exact_key, exact, rows_of, model.n_rows
        ):
            moves += 1
            continue
        # Only columns holding a resource can swap it: pairs among them, in the same (row-major) order.
        movable = np.flatnonzero(resource[chosen] >= 0)
        x, y = _pairs_of(len(movable))
        x, y = movable[x], movable[y]
        cx, cy = chosen[x], chosen[y]
        rx, ry = resource[cx], resource[cy]
        ok = (rx >= 0) & (ry >= 0) & (rx != ry)
        nx = columns_with(item_key[cx], ry)  # item set of x on y's resource
        ny = columns_with(item_key[cy], rx)
        ok &= (nx >= 0) & (ny >= 0)
        ok &= values[np.maximum(nx, 0)] + values[np.maximum(ny, 0)] == values[cx] + values[cy]
        ok &= np.minimum(nx, ny) < np.minimum(cx, cy)
        if not ok.any():
            break
        i = int(np.flatnonzero(ok)[0])
        chosen[x[i]], chosen[y[i]] = nx[i], ny[i]
        moves += 1
    return np.sort(chosen), moves


@functools.lru_cache(maxsize=512)
def _pairs_of(m: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.triu_indices(m, k=1)`` (every pair i < j, row-major), read-only and kept: each round asks for it."""
    x, y = np.triu_indices(m, k=1)
    x.setflags(write=False)
    y.setflags(write=False)
    return x, y


def _replace_once(chosen, values, exact_key, exact, rows_of, n_rows) -> bool:
    """Apply the first value-neutral replacement by an earlier column; False when there is none."""
    used = np.zeros(n_rows, dtype=bool)
    for c in chosen:
        used[rows_of(c)] = True
    for pos, c in enumerate(chosen):
        peers = np.flatnonzero((values[:c] == values[c]) & (exact_key[:c] == exact_key[c]))
        if len(peers) == 0:
            continue
        mine = rows_of(c)
        used[mine] = False
        need = mine[exact[mine]]
        for c2 in peers:
            r2 = rows_of(c2)
            if not used[r2].any() and np.isin(need, r2).all():
                chosen[pos] = c2
                return True
        used[mine] = True
    return False
