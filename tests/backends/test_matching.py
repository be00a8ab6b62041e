"""The matching backend: PyMatching reduction vs networkx, exactness at the edge of its range, lapmod vs SciPy."""

from __future__ import annotations

import time

import networkx as nx
import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from rpbench.backends import SolveOptions, get_backend
from rpbench.backends import matching as mb
from rpbench.backends._common import Clock
from rpbench.bench import synthetic
from rpbench.exceptions import SolverError
from rpbench.model import AssignmentModel, PairingModel, Status

pytest.importorskip("pymatching")
pytest.importorskip("lap")
BACKEND = get_backend("matching")
HAS_BLOSSOM_V = mb._blossom_installed()


@pytest.fixture
def no_blossom_v(monkeypatch):
    """An install without the ``blossom`` extra: what PyMatching cannot prove goes to the HiGHS MIP."""
    monkeypatch.setattr(mb, "_blossom_installed", lambda: False)


def networkx_optimum(model: PairingModel) -> tuple[float, int]:
    g = nx.Graph()
    lexi = model.objective == "cardinality_then_weight"
    for a, b, w in zip(model.col_a.tolist(), model.col_b.tolist(), model.values.tolist(), strict=True):
        if lexi or w > 0:
            g.add_edge(a, b, weight=w)
    m = nx.max_weight_matching(g, maxcardinality=lexi)
    return float(sum(g[u][v]["weight"] for u, v in m)), len(m)


def random_pairing(rng, n, density, low, high, objective):
    a, b = np.triu_indices(n, 1)
    keep = rng.random(len(a)) < density
    return PairingModel(n, a[keep], b[keep], rng.integers(low, high, keep.sum()), objective=objective)


@pytest.mark.parametrize("objective", ["weight", "cardinality_then_weight"])
@pytest.mark.parametrize("seed", range(12))
def test_pairing_equals_networkx_on_random_graphs(seed, objective):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 40))
    model = random_pairing(rng, n, float(rng.uniform(0.05, 0.5)), -50, 200, objective)
    sol = BACKEND.solve(model, SolveOptions())
    value, pairs = networkx_optimum(model)
    assert sol.status is Status.OPTIMAL and sol.objective == value
    if objective == "cardinality_then_weight":
        assert sol.cardinality == pairs


def test_pairing_is_exact_where_any_rescaling_would_round():
    # path 0-1-2-3 with w(1,2) = w(0,1) + w(2,3) ± 1 near 2^21: a rounded or rescaled weight would tie
    big = 2**21
    for delta, expected in ((+1, [1]), (-1, [0, 2])):
        v = [big, 2 * big + delta, big]
        sol = BACKEND.solve(PairingModel(4, [0, 1, 2], [1, 2, 3], v), SolveOptions())
        assert sol.chosen.tolist() == expected and sol.objective == max(2 * big + delta, 2 * big)


def test_reduction_costs_satisfy_the_star_condition():
    rng = np.random.default_rng(3)
    m = random_pairing(rng, 30, 0.3, 1, 1000, "weight")
    a, b, w = m.col_a.astype(np.int64), m.col_b.astype(np.int64), m.values.astype(np.int64)
    cost, beta = mb.reduction_costs(30, a, b, w)
    assert (cost > 0).all() and (cost == beta[a] + beta[b] - w).all()
    for v in range(30):
        incident = np.sort(np.r_[w[a == v], w[b == v]])[::-1]
        if len(incident) >= 2:
            assert 2 * beta[v] > incident[0] + incident[1]


@pytest.mark.parametrize("high", [3, 1000])
def test_each_boundary_cost_is_set_by_the_two_largest_incident_weights(high):
    """β_v = ⌊(t1 + t2) / 2⌋ + 1 read off each vertex's incident weights sorted (a weight met twice
    counts twice; low weights make ties common; isolated vertices get 1)."""
    rng = np.random.default_rng(high)
    n = 40
    a, b = rng.integers(0, n, 300), rng.integers(0, n, 300)
    w = rng.integers(1, high, 300)
    _, beta = mb.reduction_costs(n, a, b, w)
    for v in range(n):
        incident = np.sort(np.r_[w[a == v], w[b == v]])[::-1]
        t1, t2 = (list(incident[:2]) + [0, 0])[:2]
        assert beta[v] == (t1 + t2) // 2 + 1


def test_values_beyond_the_exact_range_fall_back_to_an_exact_mip(no_blossom_v):
    # 2e7 units cannot be a PyMatching weight (max 2^24 - 1): the answer must still be exact
    v = np.array([20_000_001, 40_000_001, 20_000_001])
    model = PairingModel(4, [0, 1, 2], [1, 2, 3], v)
    sol = BACKEND.solve(model, SolveOptions())
    assert sol.status is Status.OPTIMAL and sol.chosen.tolist() == [0, 2] and sol.objective == 40_000_002
    assert "HiGHS" in sol.message
    with pytest.raises(SolverError, match="exact integer range.*unit_m >= "):
        BACKEND.solve(model, SolveOptions(extra={"overflow": "error"}))


def test_common_divisor_is_divided_out_exactly():
    # multiples of 1000 (whole metres in mm) fit after division by the gcd: no fallback needed
    v = np.array([20_000, 40_001, 20_000]) * 1000
    sol = BACKEND.solve(PairingModel(4, [0, 1, 2], [1, 2, 3], v), SolveOptions(extra={"overflow": "error"}))
    assert sol.status is Status.OPTIMAL and sol.chosen.tolist() == [1]


def test_unknown_overflow_mode_is_an_error():
    with pytest.raises(SolverError, match="overflow"):
        BACKEND.solve(PairingModel(2, [0], [1], [1]), SolveOptions(extra={"overflow": "ignore"}))


def _alternating_path(m: int, heavy: int):
    """Path of 2m + 2 orders, values 1, heavy, 1, ..., 1: the m + 1 light pairs are the only maximum matching.

    A pair bonus must exceed ``m * heavy`` to prefer them, beyond the 4 x spread the PyMatching loop tries.
    """
    n = 2 * m + 2
    a = np.arange(n - 1)
    return n, a, a + 1, np.where(a % 2 == 1, heavy, 1).astype(np.int64)


def test_oracle2_lagrangian_bound_is_valid_when_the_bonus_falls_short(no_blossom_v):
    n, a, b, w = _alternating_path(8, 100)
    sel, proven, bound = mb.max_weight_max_cardinality(n, a, b, w, Clock())
    assert not proven and len(sel) == 9 and w[sel].sum() == 9  # the warm start has k* pairs
    assert bound is not None and bound >= 9  # 9 is the true optimum
    sol = BACKEND.solve(PairingModel(n, a, b, w, objective="cardinality_then_weight"), SolveOptions())
    assert sol.status is Status.OPTIMAL and len(sol.chosen) == 9 and "HiGHS MIP" in sol.message


@pytest.mark.slow
@pytest.mark.skipif(not HAS_BLOSSOM_V, reason="the blossom extra (OGDF, cppyy) is not installed")
def test_what_pymatching_cannot_prove_goes_to_blossom_v():
    n, a, b, w = _alternating_path(8, 100)
    sol = BACKEND.solve(PairingModel(n, a, b, w, objective="cardinality_then_weight"), SolveOptions())
    assert sol.status is Status.OPTIMAL and len(sol.chosen) == 9 and sol.objective == 9
    assert "Blossom V" in sol.message
    big = PairingModel(4, [0, 1, 2], [1, 2, 3], [20_000_001, 40_000_001, 20_000_001])  # beyond PyMatching's range
    sol = BACKEND.solve(big, SolveOptions())
    assert sol.status is Status.OPTIMAL and sol.chosen.tolist() == [0, 2] and "Blossom V" in sol.message


@pytest.mark.slow
@pytest.mark.skipif(not HAS_BLOSSOM_V, reason="the blossom extra (OGDF, cppyy) is not installed")
def test_large_oracle2_goes_straight_to_blossom_v(monkeypatch):
    model = synthetic.pairing(300, partners=10, objective="cardinality_then_weight")
    monkeypatch.setattr(mb, "BLOSSOM_V_FIRST", 0)
    monkeypatch.setattr(mb, "max_weight_matching", lambda *args, **kw: pytest.fail("PyMatching was called"))
    sol = BACKEND.solve(model, SolveOptions())
    assert sol.status is Status.OPTIMAL and "Blossom V" in sol.message
    assert (sol.objective, len(sol.chosen)) == networkx_optimum(model)


@pytest.mark.parametrize("seed", range(15))
def test_oracle2_bound_never_cuts_off_the_optimum(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 40))
    edges = sorted({tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(int(rng.integers(n, 3 * n)))})
    a, b = (np.array(x) for x in zip(*edges, strict=True))
    w = rng.integers(-50, 400, len(a))
    g = nx.Graph()
    g.add_weighted_edges_from(zip(a.tolist(), b.tolist(), w.tolist(), strict=True))
    best = nx.max_weight_matching(g, maxcardinality=True)
    opt = sum(g.edges[e]["weight"] for e in best)
    sel, proven, bound = mb.max_weight_max_cardinality(n, a, b, w, Clock())
    assert len(sel) == len(best)
    assert bound is None or bound >= opt
    if proven:
        assert w[sel].sum() == opt == bound


@pytest.mark.slow
def test_pymatching_timeout_falls_back_with_an_honest_status(monkeypatch, no_blossom_v):
    model = synthetic.pairing(400, partners=8, objective="cardinality_then_weight")
    monkeypatch.setattr(mb, "SMALL_GRAPH", 0)  # force the forked, deadline-guarded path

    def never(*args):
        raise mb.Timeout()

    monkeypatch.setattr(mb, "_in_child", lambda fn, args, deadline: never())
    sol = BACKEND.solve(model, SolveOptions(time_limit_s=30))
    assert "time limit" in sol.message and model.violations(sol.chosen) == []
    assert sol.objective == get_backend("highs").solve(model, SolveOptions()).objective  # HiGHS finished


def test_forked_pymatching_gives_the_in_process_answer(monkeypatch):
    model = synthetic.pairing(300, partners=10)
    inline = BACKEND.solve(model, SolveOptions())
    monkeypatch.setattr(mb, "SMALL_GRAPH", 0)
    forked = BACKEND.solve(model, SolveOptions(time_limit_s=60))
    assert forked.status is Status.OPTIMAL and forked.chosen.tolist() == inline.chosen.tolist()


def test_child_deadline_in_the_past_raises_timeout():
    with pytest.raises(mb.Timeout):
        mb._in_child(sum, ([1, 2],), deadline=0.0)


def test_child_errors_are_reported():
    with pytest.raises(SolverError, match="ZeroDivisionError"):
        mb._in_child(divmod, (1, 0), deadline=time.perf_counter() + 60)


# ------------------------------------------------------------------ assignment (lapmod)
@pytest.mark.parametrize("seed", range(10))
def test_lapmod_equals_linear_sum_assignment(seed):
    rng = np.random.default_rng(seed)
    P, V = int(rng.integers(1, 15)), int(rng.integers(1, 15))
    mask = rng.random((P, V)) < rng.uniform(0.1, 0.9)
    wait = rng.random(P) < 0.8
    mask[~wait & ~mask.any(axis=1), rng.integers(0, V)] = True  # everyone has an option
    cost = rng.integers(-(10**9), 10**6, (P, V)).astype(float)  # huge values: lap's 1e6 sentinel
    wait_value = rng.integers(-(10**9), 0, P).astype(float)
    p, v = np.nonzero(mask)
    model = AssignmentModel(
        P, V, np.r_[p, np.flatnonzero(wait)], np.r_[v, -np.ones(wait.sum(), int)], np.r_[cost[p, v], wait_value[wait]]
    )
    # dense reference: rows passengers, columns vehicles + own wait slots; forbidden = -inf value
    big = np.full((P, V + P), -np.inf)
    big[p, v] = cost[p, v]
    big[np.flatnonzero(wait), V + np.flatnonzero(wait)] = wait_value[wait]
    try:
        r, c = linear_sum_assignment(big, maximize=True)
        reference = big[r, c].sum()
    except ValueError:
        reference = None
    sol = BACKEND.solve(model, SolveOptions())
    if reference is None or not np.isfinite(reference):
        assert sol.status is Status.INFEASIBLE
    else:
        assert sol.status is Status.OPTIMAL and sol.objective == reference


def test_trip_packing_is_delegated_and_says_so():
    sol = BACKEND.solve(synthetic.trip_packing(10, 6), SolveOptions())
    assert sol.backend == "matching" and "HiGHS" in sol.message and sol.status is Status.OPTIMAL


def test_timings_are_recorded():
    sol = BACKEND.solve(synthetic.pairing(200, partners=10), SolveOptions())
    assert sol.solve_s > 0 and sol.build_s > 0 and sol.total_s == sol.build_s + sol.solve_s + sol.extract_s
