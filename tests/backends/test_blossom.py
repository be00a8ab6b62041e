"""The blossom backend (OGDF's Blossom V): exact against networkx, the doubled-graph reduction, honest failures."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from rpbench.backends import SolveOptions, get_backend
from rpbench.backends import blossom as bv
from rpbench.backends._forked import Timeout
from rpbench.backends.cardinality import maximum_cardinality_matching
from rpbench.bench import synthetic
from rpbench.exceptions import SolverError
from rpbench.model import PairingModel, Status

if not bv.BlossomBackend.is_installed():
    pytest.skip("the blossom extra (OGDF, cppyy) is not installed", allow_module_level=True)
BACKEND = get_backend("blossom")
pytestmark = pytest.mark.slow  # loading OGDF and compiling the shim takes 5-14 s once per process
OBJECTIVES = ("weight", "cardinality_then_weight")


def random_pairing(seed: int, objective: str) -> PairingModel:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 40))
    a, b = np.triu_indices(n, 1)
    keep = rng.random(len(a)) < rng.uniform(0.05, 0.4)
    return PairingModel(n, a[keep], b[keep], rng.integers(-60, 400, int(keep.sum())), objective=objective)


def networkx_optimum(model: PairingModel) -> tuple[float, int]:
    lexi = model.objective == "cardinality_then_weight"
    g = nx.Graph()
    g.add_weighted_edges_from(
        (a, b, w)
        for a, b, w in zip(model.col_a.tolist(), model.col_b.tolist(), model.values.tolist(), strict=True)
        if lexi or w > 0
    )
    m = nx.max_weight_matching(g, maxcardinality=lexi)
    return float(sum(g.edges[e]["weight"] for e in m)), len(m)


@pytest.mark.slow
@pytest.mark.parametrize("objective", OBJECTIVES)
@pytest.mark.parametrize("seed", range(40))
def test_blossom_v_equals_networkx(seed, objective):
    model = random_pairing(seed, objective)
    sol = BACKEND.solve(model, SolveOptions())
    assert sol.status is Status.OPTIMAL and model.violations(sol.chosen) == []
    assert (sol.objective, len(sol.chosen)) == networkx_optimum(model)


def test_oracle2_keeps_the_maximum_number_of_pairs_at_any_price():
    # path 0-1-2-...-17, values 1, 100, 1, ...: only the 9 light pairs are a maximum matching
    n = 18
    a = np.arange(n - 1)
    w = np.where(a % 2 == 1, 100, 1)
    sol = BACKEND.solve(PairingModel(n, a, a + 1, w, objective="cardinality_then_weight"), SolveOptions())
    assert len(sol.chosen) == 9 and sol.objective == 9
    assert BACKEND.solve(PairingModel(n, a, a + 1, w), SolveOptions()).objective == 800  # Oracle-1: 8 heavy


def test_doubled_graph_bonus_trades_weight_for_pairs():
    # triangle plus a pendant: one heavy pair (0, 1) or two light ones (0, 2), (1, 3)
    a, b, w = np.array([0, 0, 1, 1]), np.array([1, 2, 2, 3]), np.array([50, 10, 5, 10])
    assert sorted(bv.blossom_v_matching(4, a, b, w).tolist()) == [0]
    assert sorted(bv.blossom_v_matching(4, a, b, w, bonus=31).tolist()) == [1, 3]


def test_isolated_and_unused_orders_are_left_out():
    sel = bv.blossom_v_matching(10, np.array([3]), np.array([7]), np.array([5]))
    assert sel.tolist() == [0]
    assert bv.blossom_v_matching(5, np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)).size == 0


def test_a_graph_without_a_perfect_matching_is_an_error():
    with pytest.raises(SolverError, match="no perfect matching"):
        bv.min_cost_perfect_matching(3, np.array([0, 1]), np.array([1, 2]), np.array([1, 1]))


def test_costs_beyond_int64_are_refused():
    with pytest.raises(SolverError, match="overflow 64-bit"):
        bv.blossom_v_matching(2, np.array([0]), np.array([1]), np.array([2**59]))


def test_time_limit_returns_edmonds_matching_for_oracle2(monkeypatch):
    model = synthetic.pairing(200, partners=8, objective="cardinality_then_weight")

    def never(*args, **kw):
        raise Timeout()

    monkeypatch.setattr(bv, "run_in_child", never)
    sol = BACKEND.solve(model, SolveOptions(time_limit_s=5))
    assert sol.status is Status.TIME_LIMIT and "time limit" in sol.message
    assert len(sol.chosen) == maximum_cardinality_matching(model.n_orders, model.col_a, model.col_b).size
    assert model.violations(sol.chosen) == []
    one = BACKEND.solve(synthetic.pairing(200, partners=8), SolveOptions(time_limit_s=5))
    assert one.status is Status.TIME_LIMIT and len(one.chosen) == 0


def test_forked_solve_gives_the_in_process_answer():
    model = synthetic.pairing(300, partners=10, objective="cardinality_then_weight")
    inline = BACKEND.solve(model, SolveOptions())
    forked = BACKEND.solve(model, SolveOptions(time_limit_s=120))
    assert forked.status is Status.OPTIMAL and forked.chosen.tolist() == inline.chosen.tolist()


def test_a_short_pair_count_is_an_error_not_an_answer(monkeypatch):
    model = synthetic.pairing(60, partners=6, objective="cardinality_then_weight")
    monkeypatch.setattr(bv, "run_in_child", lambda fn, args, deadline, solver: fn(*args)[:-1])
    with pytest.raises(SolverError, match="proven maximum"):
        BACKEND.solve(model, SolveOptions())


def test_other_structures_are_delegated():
    sol = BACKEND.solve(synthetic.assignment(20, 8), SolveOptions())
    assert sol.backend == "blossom" and sol.status is Status.OPTIMAL
    assert sol.objective == get_backend("highs").solve(synthetic.assignment(20, 8), SolveOptions()).objective
