"""Solver-independent choice among tied optima (rpbench.sim.ties)."""

from __future__ import annotations

import itertools

import numpy as np

from rpbench.model import AssignmentModel, Status, TripPackingModel, make_solution
from rpbench.sim.ties import canonicalize


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


def test_pairs_of_equals_triu_indices_and_is_read_only():
    from rpbench.sim.ties import _pairs_of

    for m in range(8):
        x, y = _pairs_of(m)
        ex, ey = np.triu_indices(m, k=1)
        assert np.array_equal(x, ex) and np.array_equal(y, ey) and not x.flags.writeable


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
