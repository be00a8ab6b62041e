"""Solver-independent choice among tied optima (rpbench.sim.ties)."""

from __future__ import annotations

import itertools

import numpy as np

from rpbench.model import AssignmentModel, Status, TripPackingModel, make_solution
from rpbench.sim.ties import _repair, canonicalize


def optimal(model, chosen):
    return make_solution(model, chosen, Status.OPTIMAL, "test")


def test_interchangeable_vehicles_go_to_passengers_in_order():
    # Two passengers, three identical vehicles (same value for everybody), plus waiting options.
    cp = [0, 0, 0, 0, 1, 1, 1, 1]
    cv = [0, 1, 2, -1, 0, 1, 2, -1]
    vals = [-5, -5, -5, -1000, -7, -7, -7, -1000]
    m = AssignmentModel(2, 3, cp, cv, vals)
    for start in ([2, 5], [1, 6], [2, 4], [0, 5]):
        fixed, _ = canonicalize(m, optimal(m, start))
        assert fixed.chosen.tolist() == [0, 5]  # p0 -> v0, p1 -> v1
        assert fixed.objective == optimal(m, start).objective


def test_swap_between_two_passengers():
    # p0 and p1 share an origin: vehicles 0 and 1 are worth the same to both, so swapping is value-neutral.
    cp = [0, 0, 1, 1]
    cv = [0, 1, 0, 1]
    m = AssignmentModel(2, 2, cp, cv, [-3, -4, -3, -4])
    fixed, moves = canonicalize(m, optimal(m, [1, 2]))  # p0 -> v1, p1 -> v0
    assert fixed.chosen.tolist() == [0, 3] and moves == 1


def test_no_move_without_a_tie():
    m = AssignmentModel(2, 2, [0, 0, 1, 1], [0, 1, 0, 1], [-3, -4, -4, -3])
    sol = optimal(m, [0, 3])
    fixed, moves = canonicalize(m, sol)
    assert moves == 0 and fixed is sol


def test_non_optimal_solutions_are_left_alone():
    m = AssignmentModel(1, 2, [0, 0], [0, 1], [-5, -5])
    sol = make_solution(m, [1], Status.TIME_LIMIT, "test")
    assert canonicalize(m, sol)[0] is sol


def test_trip_packing_vehicle_swap_and_replace():
    # Identical vehicles 0 and 1; a pair trip {0,1} and a single trip {2}.
    cv = [0, 0, 1, 1]
    r1 = [0, 2, 0, 2]
    r2 = [1, -1, 1, -1]
    m = TripPackingModel(3, 2, cv, r1, r2, [10, 4, 10, 4])
    fixed, _ = canonicalize(m, optimal(m, [1, 2]))  # {2} on v0, {0,1} on v1
    assert fixed.chosen.tolist() == [0, 3]


def test_canonical_choice_is_independent_of_the_start_on_symmetric_models():
    rng = np.random.default_rng(0)
    for _ in range(20):
        n_p, n_groups = 3, 2
        # vehicles come in groups of identical copies
        group_vals = rng.integers(-20, 0, size=(n_p, n_groups))
        copies = 2
        cp, cv, vals = [], [], []
        for p in range(n_p):
            for g in range(n_groups):
                for c in range(copies):
                    cp.append(p), cv.append(g * copies + c), vals.append(group_vals[p, g])
            cp.append(p), cv.append(-1), vals.append(-1000)
        m = AssignmentModel(n_p, n_groups * copies, cp, cv, vals)
        # enumerate every optimal solution, canonicalise each: all must land on the same one
        cols_of = [np.flatnonzero(m.col_passenger == p) for p in range(n_p)]
        sols = []
        for combo in itertools.product(*cols_of):
            if not m.violations(list(combo)):
                sols.append((m.objective_of(list(combo)), combo))
        best = max(s[0] for s in sols)
        outcomes = {tuple(canonicalize(m, optimal(m, list(c)))[0].chosen) for v, c in sols if v == best}
        assert len(outcomes) == 1


def _reference_swaps(model, chosen):
    """The resource swaps of the canonicalisation, over every pair of chosen columns in row-major order."""
    by_key = {(int(p), int(v)): c for c, (p, v) in enumerate(zip(model.col_passenger, model.col_vehicle, strict=True))}
    values = model.values
    chosen = sorted(chosen)
    while True:
        for i, j in itertools.combinations(range(len(chosen)), 2):
            cx, cy = chosen[i], chosen[j]
            rx, ry = int(model.col_vehicle[cx]), int(model.col_vehicle[cy])
            if rx < 0 or ry < 0 or rx == ry:
                continue
            nx = by_key.get((int(model.col_passenger[cx]), ry))
            ny = by_key.get((int(model.col_passenger[cy]), rx))
            if nx is None or ny is None or values[nx] + values[ny] != values[cx] + values[cy]:
                continue
            if min(nx, ny) < min(cx, cy):
                chosen[i], chosen[j] = nx, ny
                chosen = sorted(chosen)
                break
        else:
            return chosen


def test_swaps_match_a_pairwise_reference_with_waiting_columns_among_the_chosen():
    # Distinct values per passenger (no replacement moves), waits chosen next to assignments.
    rng = np.random.default_rng(7)
    moved = 0
    for _ in range(30):
        n_p, n_v = 6, 4
        cp, cv, vals = [], [], []
        for p in range(n_p):
            rank = rng.permutation(n_v) if p % 2 else np.arange(n_v)  # equal rankings make swaps value-neutral
            for v in range(n_v):
                cp.append(p), cv.append(v), vals.append(-10 * int(rank[v]) - p)
            cp.append(p), cv.append(-1), vals.append(-1000 - p)
        m = AssignmentModel(n_p, n_v, cp, cv, vals)
        perm = rng.permutation(n_v)
        start = [p * (n_v + 1) + (int(perm[p]) if p < n_v else n_v) for p in range(n_p)]
        got = canonicalize(m, optimal(m, start))[0].chosen.tolist()
        assert got == _reference_swaps(m, start)
        moved += got != sorted(start)
    assert moved > 0


def _numpy_repair(model, chosen, resource, items):
    """The repair as numpy passes (the compiled kernel's reference): replace moves, then row-major swaps."""
    values = model.values
    start, rows = model.column_rows()
    exact = model.row_exact()
    n = model.n_cols
    exact_key = np.full(n, -1, dtype=np.int64)
    for c in range(n):
        mine = rows[start[c] : start[c + 1]]
        if exact[mine].any():
            exact_key[c] = mine[exact[mine]][0]
    key = np.zeros(n, dtype=np.int64)
    for a in items + (resource,):
        key = key * (int(a.max(initial=0)) + 2) + (a + 1)
    by_key = {int(k): c for c, k in enumerate(key)}
    chosen = sorted(int(c) for c in chosen)
    moves = 0
    while True:
        used = np.zeros(model.n_rows, dtype=bool)
        for c in chosen:
            used[rows[start[c] : start[c + 1]]] = True
        replaced = False
        for pos, c in enumerate(chosen):
            mine = rows[start[c] : start[c + 1]]
            used[mine] = False
            for c2 in np.flatnonzero((values[:c] == values[c]) & (exact_key[:c] == exact_key[c])):
                r2 = rows[start[c2] : start[c2 + 1]]
                if not used[r2].any() and np.isin(mine[exact[mine]], r2).all():
                    chosen[pos], replaced = int(c2), True
                    break
            if replaced:
                break
            used[mine] = True
        if replaced:
            moves += 1
            chosen.sort()
            continue
        for i, j in itertools.combinations(range(len(chosen)), 2):
            cx, cy = chosen[i], chosen[j]
            rx, ry = int(resource[cx]), int(resource[cy])
            if rx < 0 or ry < 0 or rx == ry:
                continue
            nx = by_key.get(int(key[cx] - (rx + 1) + ry + 1))
            ny = by_key.get(int(key[cy] - (ry + 1) + rx + 1))
            if nx is None or ny is None or values[nx] + values[ny] != values[cx] + values[cy]:
                continue
            if min(nx, ny) < min(cx, cy):
                chosen[i], chosen[j] = nx, ny
                break
        else:
            return chosen, moves
        moves += 1
        chosen.sort()


def _random_tied_assignment(rng):
    """Passengers valuing vehicles from a few levels (many ties), a wait column each; a feasible start."""
    n_p, n_v = int(rng.integers(1, 7)), int(rng.integers(1, 7))
    cp, cv, vals = [], [], []
    for p in range(n_p):
        for v in range(n_v):
            if rng.random() < 0.7:
                cp.append(p), cv.append(v), vals.append(-int(rng.integers(1, 3)))
        cp.append(p), cv.append(-1), vals.append(-int(rng.integers(1, 4)))
    m = AssignmentModel(n_p, n_v, cp, cv, vals)
    free, start = set(range(n_v)), []
    for p in rng.permutation(n_p):
        cols = [c for c in np.flatnonzero(m.col_passenger == p) if m.col_vehicle[c] < 0 or m.col_vehicle[c] in free]
        c = int(rng.choice(cols))
        free.discard(int(m.col_vehicle[c]))
        start.append(c)
    return m, start


def test_the_compiled_repair_matches_the_numpy_passes_on_tied_assignments():
    rng = np.random.default_rng(11)
    moved = 0
    for _ in range(300):
        m, start = _random_tied_assignment(rng)
        resource, items = m.col_vehicle, (m.col_passenger,)  # the model's int32 columns, as canonicalize passes them
        got, moves = _repair(m, np.array(start, np.int64), resource, np.stack(items))
        want, want_moves = _numpy_repair(m, start, resource, items)
        assert got.tolist() == want and moves == want_moves
        moved += moves > 0
    assert moved > 50


def test_the_compiled_repair_matches_the_numpy_passes_on_trip_packing():
    rng = np.random.default_rng(12)
    for _ in range(200):
        n_r, n_v = int(rng.integers(2, 6)), int(rng.integers(1, 4))
        trips = [(a, -1) for a in range(n_r)] + [(a, b) for a in range(n_r) for b in range(a + 1, n_r)]
        cv, r1, r2, vals = [], [], [], []
        for v in range(n_v):
            for a, b in trips:
                if rng.random() < 0.6:
                    cv.append(v), r1.append(a), r2.append(b), vals.append(int(rng.integers(1, 3)))
        if not cv:
            continue
        m = TripPackingModel(n_r, n_v, cv, r1, r2, vals)
        used, start = set(), []
        for c in rng.permutation(m.n_cols):
            rows = set(m.column_rows()[1][m.column_rows()[0][c] : m.column_rows()[0][c + 1]].tolist())
            if not rows & used:
                used |= rows
                start.append(int(c))
        resource = m.col_vehicle
        items = (m.col_request1, m.col_request2)
        got, moves = _repair(m, np.array(start, np.int64), resource, np.stack(items))
        want, want_moves = _numpy_repair(m, start, resource, items)
        assert got.tolist() == want and moves == want_moves
