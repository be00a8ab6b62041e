"""Edmonds' maximum-cardinality matching and its Tutte-Berge certificate (rpbench.backends.cardinality)."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rpbench.backends import cardinality as card
from rpbench.exceptions import SolverError


@st.composite
def graphs(draw, max_n=24):
    n = draw(st.integers(1, max_n))
    edges = draw(
        st.sets(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)).filter(lambda e: e[0] < e[1]), max_size=3 * n)
    )
    a, b = (np.array(x, np.int64) for x in zip(*sorted(edges), strict=True)) if edges else (np.zeros(0, np.int64),) * 2
    return n, a, b


def _networkx_matching_number(n, a, b) -> int:
    g = nx.Graph()
    g.add_nodes_from(range(n))
    g.add_edges_from(zip(a.tolist(), b.tolist(), strict=True))
    return len(nx.max_weight_matching(g, maxcardinality=True))


def _assert_matching(n, a, b, mate):
    v = np.flatnonzero(mate >= 0)
    assert np.all(mate[mate[v]] == v)
    edges = set(zip(a.tolist(), b.tolist(), strict=True)) | set(zip(b.tolist(), a.tolist(), strict=True))
    assert all((x, int(mate[x])) in edges for x in v)


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(graphs())
def test_matches_networkx_and_certifies_itself(graph):
    n, a, b = graph
    result = card.maximum_cardinality_matching(n, a, b)
    _assert_matching(n, a, b, result.mate)
    assert result.size == _networkx_matching_number(n, a, b)
    # the Tutte-Berge set is an independent proof: nothing bigger exists
    assert card.tutte_berge_bound(n, a, b, result.tutte_set) == result.size


@settings(max_examples=150, deadline=None)
@given(graphs(max_n=40), st.randoms(use_true_random=False))
def test_augments_any_start_to_the_maximum(graph, rnd):
    n, a, b = graph
    mate = np.full(n, -1, np.int64)
    for i in rnd.sample(range(len(a)), len(a)):  # a random, not necessarily maximal, matching
        if rnd.random() < 0.5 and mate[a[i]] < 0 and mate[b[i]] < 0:
            mate[a[i]], mate[b[i]] = b[i], a[i]
    result = card.maximum_cardinality_matching(n, a, b, start=mate)
    _assert_matching(n, a, b, result.mate)
    assert result.size == _networkx_matching_number(n, a, b)
    assert result.size >= int((mate >= 0).sum() // 2)


def test_odd_cycles_need_blossoms():
    # a 5-cycle with a pendant path: BFS without blossom contraction misses the augmenting path
    a = np.array([0, 1, 2, 3, 4, 0, 5])
    b = np.array([1, 2, 3, 4, 0, 5, 6])
    start = card.mate_of(7, np.array([1, 3, 5]), np.array([2, 4, 6]))
    result = card.maximum_cardinality_matching(7, a, b, start=start)
    assert result.size == 3 and card.tutte_berge_bound(7, a, b, result.tutte_set) == 3


def test_triangles_bound_is_tight_where_the_fractional_one_is_not():
    # two triangles joined by an edge: fractional matching 3, matching number 3; two apart: 2 (not 3)
    a, b = np.array([0, 0, 1, 3, 3, 4]), np.array([1, 2, 2, 4, 5, 5])
    result = card.maximum_cardinality_matching(6, a, b)
    assert result.size == 2 and len(result.tutte_set) == 0
    assert card.tutte_berge_bound(6, a, b, result.tutte_set) == 2


def test_a_wrong_tutte_set_gives_a_weaker_bound():
    # a star: the centre is the Tutte set (bound 1); the empty set only bounds by n // 2 = 2
    a, b = np.zeros(4, np.int64), np.arange(1, 5)
    assert card.maximum_cardinality_matching(5, a, b).tutte_set.tolist() == [0]
    assert card.tutte_berge_bound(5, a, b, np.array([0])) == 1
    assert card.tutte_berge_bound(5, a, b, np.zeros(0, np.int64)) == 2


def test_start_that_is_not_a_matching_is_rejected():
    a, b = np.array([0, 1]), np.array([1, 2])
    with pytest.raises(ValueError, match="not a matching"):
        card.maximum_cardinality_matching(3, a, b, start=np.array([2, -1, 0]))  # (0, 2) is no edge
    with pytest.raises(ValueError, match="mate array"):
        card.maximum_cardinality_matching(3, a, b, start=np.array([1, 0]))


def test_edge_indices_rejects_a_non_edge():
    a, b = np.array([0, 2]), np.array([1, 3])
    assert card.edge_indices(4, a, b, np.array([3, 1]), np.array([2, 0])).tolist() == [0, 1]
    with pytest.raises(SolverError, match="not a candidate pair"):
        card.edge_indices(4, a, b, np.array([0]), np.array([3]))
    assert card.columns_of_mate(4, a, b, card.mate_of(4, np.array([2]), np.array([3]))).tolist() == [1]
