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


def maximum(a, b, w) -> int:
    """The maximum weight of a matching, by networkx's exact blossom (an independent reference)."""
    g = nx.Graph()
    g.add_weighted_edges_from(zip(a.tolist(), b.tolist(), w.astype(int).tolist(), strict=True))
    return sum(g[u][v]["weight"] for u, v in nx.max_weight_matching(g))


def proves(proof, target) -> bool:
    """``bound-optimal``'s verdict on a target: no matching found above it, and a bound below ``target + 1``."""
    return proof.best <= target and proof.upper < np.floor(target) + 1 - 1e-6


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("size", [(30, 100), (80, 400)])
def test_the_proof_agrees_with_networkx_and_fails_one_unit_below(seed, size):
    """The true maximum is proven by a dual certificate alone (the exact separator leaves no fractional
    optimum standing); one unit below it fails."""
    n, a, b, w = random_graph(seed, *size)
    best = maximum(a, b, w)
    proof = prove_maximum(n, a, b, w, best)
    assert proves(proof, best) and proof.mip_edges is None
    assert not proves(prove_maximum(n, a, b, w, best - 1), best - 1)


def test_a_graph_whose_odd_components_are_not_violated_is_proven_by_the_exact_separator():
    """On this graph the LP's fractional solutions reach a point where no odd component or odd cycle of the
    fractional edges is a violated odd set; the exact separator finds some and the dual certificate closes
    on the maximum without an exact solver."""
    n, a, b, w = random_graph(21, 80, 400)
    best = maximum(a, b, w)
    proof = prove_maximum(n, a, b, w, best)
    assert proof.separated > 0 and proof.mip_edges is None
    assert proves(proof, best) and not proves(prove_maximum(n, a, b, w, best - 1), best - 1)


def stall(monkeypatch):
    """A cutting-plane loop that never finds an odd set: it stalls at the degree LP."""
    from rpbench.check import matching

    monkeypatch.setattr(matching, "_cutting_sets", lambda n, a, b, x: ([], 0))


def no_blossom_v(monkeypatch):
    """The optional Blossom V extra as if not installed."""
    from rpbench.backends import blossom
    from rpbench.exceptions import SolverNotInstalledError

    def missing(*args, **kwargs):
        raise SolverNotInstalledError("not installed")

    monkeypatch.setattr(blossom, "blossom_v_matching", missing)


def assert_decided_by(monkeypatch, seed, method):
    n, a, b, w = random_graph(seed, n=60, m=240)
    best = maximum(a, b, w)
    proof = prove_maximum(n, a, b, w, best)
    # proven: nothing beats the maximum (the matching found may be smaller: the exact code saw only the edges
    # that a matching worth more than the target could use)
    assert proof.best <= best <= proof.upper < best + 1
    assert proof.mip_edges is not None and proof.mip_edges < len(a) / 2 and method in proof.method
    proof = prove_maximum(n, a, b, w, best - 1)
    assert proof.best > best - 1  # a target below the maximum is caught


@pytest.mark.parametrize("seed", [0, 4, 6, 7])  # graphs whose degree LP is fractional at the maximum
def test_a_stalled_cutting_plane_loop_still_decides_by_reduced_cost_fixing(monkeypatch, seed):
    """With no odd set ever found, the loop stalls at the degree LP: the dual then fixes every edge whose slack
    exceeds the gap, HiGHS's MIP (Blossom V not installed) decides the rest, and the answer is still the
    maximum, either way of the target."""
    stall(monkeypatch)
    no_blossom_v(monkeypatch)
    assert_decided_by(monkeypatch, seed, "HiGHS MIP")


@pytest.mark.slow  # loads OGDF through cppyy (a C++ compile, seconds)
@pytest.mark.parametrize("seed", [0, 4])
def test_a_stalled_loop_is_decided_by_blossom_v_when_installed(monkeypatch, seed):
    """With the ``blossom`` extra, Blossom V (not the bound run's PyMatching) decides the edges left."""
    from rpbench.backends.blossom import BlossomBackend

    if BlossomBackend.missing_libraries():
        pytest.skip("the blossom extra (OGDF through cppyy) is not installed")
    stall(monkeypatch)
    assert_decided_by(monkeypatch, seed, "Blossom V")


def test_exact_separation_finds_a_violated_set_inside_an_odd_component_that_is_not():
    """A triangle at 0.45 a side with a path 2-3-4 at 0.1 hanging off it: the fractional component {0..4} is
    odd but not violated (x(E) = 1.55 <= 2), so the heuristic has nothing; its triangle is (1.35 > 1)."""
    from rpbench.check.matching import _cutting_sets, _odd_components
    from rpbench.check.separation import is_violated_blossom, violated_blossoms

    a, b = np.array([0, 1, 0, 2, 3]), np.array([1, 2, 2, 3, 4])
    x = np.array([0.45, 0.45, 0.45, 0.1, 0.1])
    (component,) = _odd_components(5, a, b)
    assert sorted(component.tolist()) == [0, 1, 2, 3, 4] and not is_violated_blossom(5, a, b, x, component)
    assert [sorted(s.tolist()) for s in violated_blossoms(5, a, b, x)] == [[0, 1, 2]]
    found, exact = _cutting_sets(5, a, b, x)
    assert exact == 1 and [sorted(s.tolist()) for s in found] == [[0, 1, 2]]


def fractional_point(seed: int, n: int = 9):
    """A random point of the fractional matching polytope on a small graph (degrees <= 1): a triangle on
    vertices 0, 1, 2 at 0.35-0.5 a side (a violated blossom inequality, perhaps not the most violated one),
    the other edges random within the degrees left."""
    rng = np.random.default_rng(seed)
    _, a, b, _ = random_graph(seed, n=n, m=3 * n)
    other = ~(np.isin(a, [0, 1, 2]) & np.isin(b, [0, 1, 2]))
    a, b = np.r_[0, 1, 0, a[other]], np.r_[1, 2, 2, b[other]]
    x = np.r_[0.35 + 0.15 * rng.random(3), rng.random(int(other.sum())) ** 2]
    left = 1.0 - np.bincount(np.r_[a[:3], b[:3]], weights=np.r_[x[:3], x[:3]], minlength=n)
    want = np.bincount(np.r_[a[3:], b[3:]], weights=np.r_[x[3:], x[3:]], minlength=n)
    scale = np.minimum(left / np.maximum(want, 1e-12), 1.0)
    x[3:] *= np.minimum(scale[a[3:]], scale[b[3:]])  # every degree now <= 1
    return n, a, b, x


def most_violation(n, a, b, x) -> float:
    """The largest violation ``x(E(S)) - (|S| - 1)/2`` over every odd S of 3 or more vertices (0 if none)."""
    import itertools

    from rpbench.check.separation import inside_weight

    most = 0.0
    for size in range(3, n + 1, 2):
        for members in itertools.combinations(range(n), size):
            most = max(most, inside_weight(a, b, x, np.array(members), n) - (size - 1) / 2)
    return most


@pytest.mark.parametrize("seed", range(12))
def test_the_separator_returns_odd_violated_sets_and_a_most_violated_one(seed):
    """Against every odd subset of a 9-vertex graph: each set returned is odd and violated, and one of them is
    as violated as the most violated subset (Padberg and Rao); none is returned only when none exists."""
    from rpbench.check.separation import VIOLATION_TOL, inside_weight, violated_blossoms

    n, a, b, x = fractional_point(seed)
    found = violated_blossoms(n, a, b, x)
    violation = [inside_weight(a, b, x, s, n) - (len(s) - 1) / 2 for s in found]
    assert all(len(np.unique(s)) == len(s) and len(s) % 2 == 1 and len(s) >= 3 for s in found)
    assert all(v > VIOLATION_TOL for v in violation)
    degree = np.bincount(np.r_[a, b], weights=np.r_[x, x], minlength=n)
    assert degree.max() <= 1 + 1e-12 and x[:3].sum() > 1  # a point of the LP, its planted triangle violated
    assert max(violation) == pytest.approx(most_violation(n, a, b, x), abs=1e-5)


@pytest.mark.parametrize("seed", range(4))
def test_the_separator_finds_nothing_in_the_matching_polytope(seed):
    """An average of matchings satisfies every blossom inequality: no set comes back."""
    from rpbench.check.separation import violated_blossoms

    n, a, b, _ = random_graph(seed, n=9, m=27)
    rng = np.random.default_rng(seed)
    x = np.zeros(len(a))
    for _ in range(4):  # four maximum matchings under random weights, averaged
        h = nx.Graph()
        h.add_weighted_edges_from(zip(a.tolist(), b.tolist(), rng.random(len(a)).tolist(), strict=True))
        chosen = {frozenset(e) for e in nx.max_weight_matching(h)}
        x += 0.25 * np.array([frozenset((u, v)) in chosen for u, v in zip(a.tolist(), b.tolist(), strict=True)])
    assert most_violation(n, a, b, x) <= 1e-9 and violated_blossoms(n, a, b, x) == []


@pytest.mark.parametrize("seed", range(10))
def test_the_gomory_hu_tree_is_a_cut_tree(seed):
    """Each tree edge's fundamental cut has the tree edge's capacity, and the minimum cut between any two nodes
    (networkx's) is the smallest capacity on their tree path."""
    import itertools

    from rpbench.check.separation import _fundamental_sides, _gomory_hu_tree

    rng = np.random.default_rng(seed)
    k = int(rng.integers(3, 12))
    u, v = rng.integers(0, k, 3 * k), rng.integers(0, k, 3 * k)
    u, v = u[u != v], v[u != v]
    cap = rng.integers(1, 20, len(u))
    parent, capacity = _gomory_hu_tree(k, u, v, cap)
    g = nx.Graph()
    g.add_nodes_from(range(k))
    for x, y, c in zip(u.tolist(), v.tolist(), cap.tolist(), strict=True):
        g.add_edge(x, y, capacity=g.edges[x, y]["capacity"] + c if g.has_edge(x, y) else c)
    for node, side in enumerate(_fundamental_sides(parent), start=1):
        inside = np.isin(u, side)
        assert cap[inside != np.isin(v, side)].sum() == capacity[node]
    tree = nx.Graph((i, int(parent[i]), {"c": int(capacity[i])}) for i in range(1, k))
    assert nx.is_tree(tree) and tree.number_of_nodes() == k
    for s, t in itertools.combinations(range(k), 2):
        path = nx.shortest_path(tree, s, t)
        expected = nx.minimum_cut_value(g, s, t) if nx.has_path(g, s, t) else 0
        assert min(tree.edges[p, q]["c"] for p, q in itertools.pairwise(path)) == expected


def test_overlapping_odd_sets_hold_exactly_their_inside_edges():
    """Nested sets (the separator's are laminar) each get every edge with both ends inside, once."""
    from rpbench.check.matching import OddSets

    n, a, b, _ = random_graph(3, n=12, m=40)
    sets = [np.array([0, 1, 2]), np.array([0, 1, 2, 3, 4]), np.array([5, 6, 7]), np.array([2, 3, 5, 6, 7])]
    odd = OddSets(n, a, b)
    odd.add(sets)
    rows = odd.rows().toarray()
    for row, s in zip(rows, sets, strict=True):
        assert (row == (np.isin(a, s) & np.isin(b, s))).all()
    assert odd.capacity.tolist() == [1, 2, 1, 2]


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
