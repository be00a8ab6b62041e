"""``bound-optimal``: the checker's own enumeration of the bound's graph, its proof of the maximum, and a forged
bound (a matching short of the maximum, or one over a graph missing pairs) written by rpbench's own code."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from check.tamper import build
from rpbench.check import check_tree
from rpbench.check.folder import read_folder
from rpbench.check.matching import bound_graph, prove_maximum
from rpbench.harness import comparison
from rpbench.oracle.pairs import bound_rules, find_candidates
from rpbench.oracle.solve import oracle_model, solve_oracle
from rpbench.scenarios import ScenarioRequest

nx = pytest.importorskip("networkx")


def random_graph(seed: int, n: int = 40, m: int = 120):
    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, n, m), rng.integers(0, n, m)
    keep = a != b
    a, b = np.minimum(a, b)[keep], np.maximum(a, b)[keep]
    _, first = np.unique(a * n + b, return_index=True)
    return n, a[first], b[first], rng.integers(1, 1000, len(first)).astype(np.float64)


@pytest.mark.parametrize("seed", range(8))
def test_the_proof_finds_the_maximum_of_random_graphs(seed):
    """The checker's matching is the maximum (networkx's exact blossom) and its dual bound closes on it."""
    n, a, b, w = random_graph(seed)
    g = nx.Graph()
    g.add_weighted_edges_from(zip(a.tolist(), b.tolist(), w.astype(int).tolist(), strict=True))
    best = sum(g[u][v]["weight"] for u, v in nx.max_weight_matching(g))
    proof = prove_maximum(n, a, b, w, best)
    assert proof.best == best and best <= proof.upper < best + 1
    proof = prove_maximum(n, a, b, w, best - 1)  # a target below the maximum is caught
    assert proof.best > best - 1


@pytest.mark.parametrize("seed", [0, 4, 6, 7])  # graphs whose degree LP is fractional at the maximum
def test_a_stalled_cutting_plane_loop_still_decides_by_reduced_cost_fixing(monkeypatch, seed):
    """With no odd set ever found, the loop stalls at the degree LP: the dual then fixes every edge whose slack
    exceeds the gap, the MIP decides the rest, and the answer is still the maximum, either way of the target."""
    from rpbench.check import matching

    monkeypatch.setattr(matching, "_odd_components", lambda n, a, b: [])
    n, a, b, w = random_graph(seed, n=60, m=240)
    g = nx.Graph()
    g.add_weighted_edges_from(zip(a.tolist(), b.tolist(), w.astype(int).tolist(), strict=True))
    best = sum(g[u][v]["weight"] for u, v in nx.max_weight_matching(g))
    proof = prove_maximum(n, a, b, w, best)
    # proven: nothing beats the maximum (the matching found may be smaller: the MIP saw only the edges that
    # a matching worth more than the target could use)
    assert proof.best <= best <= proof.upper < best + 1
    assert proof.mip_edges is not None and proof.mip_edges < len(a) / 2
    proof = prove_maximum(n, a, b, w, best - 1)
    assert proof.best > best - 1  # a target below the maximum is caught


def test_odd_sets_are_odd_components_and_odd_cycles_of_even_ones():
    """A triangle with a pendant edge is an even component holding the odd set {0, 1, 2}; a path of three
    nodes is an odd component; a square is even and bipartite: no odd set."""
    from rpbench.check.matching import _odd_components

    a = np.array([0, 1, 0, 2, 5, 6, 10, 11, 12, 10])
    b = np.array([1, 2, 2, 3, 6, 7, 11, 12, 13, 13])
    found = sorted(s.tolist() for s in _odd_components(14, a, b))
    assert found == [[0, 1, 2], [5, 6, 7]]


def test_the_checker_enumerates_the_bound_graph_the_run_used(tmp_path):
    """The checker's graph has exactly the run's candidate pairs, with their weights."""
    folder = build(tmp_path / "toy", ["bound"])
    f = read_folder(folder)
    a, b, w = bound_graph(f)
    sc = ScenarioRequest("toy", sample=0.25, seed=3).build()
    cands = find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    mine = dict(zip(zip(np.minimum(a, b).tolist(), np.maximum(a, b).tolist(), strict=True), w.tolist(), strict=True))
    theirs = dict(zip(zip(cands.low.tolist(), cands.high.tolist(), strict=True), cands.saving_m.tolist(), strict=True))
    assert mine.keys() == theirs.keys() and len(mine) > 50
    assert np.allclose([mine[k] for k in theirs], list(theirs.values()), atol=1e-6)


def forged(monkeypatch, forge):
    """Make run_comparison write its bound run through ``forge(scenario, result, candidates)``."""
    solve_offline = comparison.solve_offline

    def patched(scenario, entries, preset):
        out = solve_offline(scenario, entries, preset)
        cands = find_candidates(scenario.network.distances(), scenario.orders, bound_rules(scenario.params))
        out["bound"] = forge(scenario, out["bound"], cands)
        return out

    monkeypatch.setattr(comparison, "solve_offline", patched)


def without_best_pairs(scenario, result, cands, k: int = 3):
    """The true matching minus its ``k`` best pairs; objective, bound and pairs as a solver would report them."""
    sol, values = result.solution, result.model.values
    best = np.argsort(values[sol.chosen])[-k:]
    chosen = np.delete(sol.chosen, best)
    objective = float(values[chosen].sum())
    solution = dataclasses.replace(sol, chosen=chosen, objective=objective, bound=objective, gap=0.0)
    pairs = result.pairs.drop(result.pairs.index[best]).reset_index(drop=True)
    return dataclasses.replace(result, solution=solution, pairs=pairs)


def on_fewer_candidates(scenario, result, cands, k: int = 3):
    """The maximum over a candidate set missing the ``k`` best pairs of the true matching."""
    _, rows = oracle_model(cands, 1)  # the model's column -> candidate row
    chosen = result.solution.chosen
    drop = rows[chosen[np.argsort(result.model.values[chosen])[-k:]]]
    return solve_oracle(scenario, 1, "matching", candidates=cands.take(np.setdiff1d(np.arange(len(cands)), drop)))


@pytest.mark.parametrize("forge", [without_best_pairs, on_fewer_candidates])
def test_a_forged_bound_fails_bound_optimal(monkeypatch, tmp_path, forge):
    """A bound short of the maximum, every table written by rpbench's own code (kpis, competitive ratios,
    hourly, report, digest), fails ``bound-optimal`` and nothing else; the true bound passes."""
    clean = build(tmp_path / "clean", ["mb", "bound"])
    (found,) = check_tree(clean)
    assert found.status == "ok" and found.runs[-1].checked["bound_graph_pairs"] > 0
    forged(monkeypatch, forge)
    folder = build(tmp_path / "forged", ["mb", "bound"])
    (found,) = check_tree(folder)
    failed = {c.run: set(c.violations) for c in found.checks if not c.ok}
    assert failed == {"bound": {"bound-optimal"}}
    (message,) = found.runs[-1].violations["bound-optimal"]
    assert "more than the reported bound" in message
