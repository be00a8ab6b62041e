"""Candidate pairs of the oracle (docs/algorithms.md §4.2) against a brute-force enumeration.

The reference below loops over every ordered pair of orders in plain Python
and recomputes POOL (§1.1) from the formulas, with shortest paths summed arc
by arc -- no code shared with the vectorised enumeration besides the
distance matrix.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rpbench.exceptions import ParameterError
from rpbench.oracle.pairs import PairRules, find_candidates
from rpbench.scenarios.base import Orders
from rpbench.scenarios.toy import grid_network

TOL = 1e-9


@pytest.fixture(scope="module")
def grid():
    net = grid_network(8, seed=3)
    return net, net.distances(use_cache=False)


def make_orders(origin, destination, request_s, order_id=None) -> Orders:
    n = len(origin)
    ids = np.arange(n) if order_id is None else np.asarray(order_id)
    srt = np.lexsort((ids, np.asarray(request_s, float)))
    return Orders(
        order_id=np.asarray(ids, np.int64)[srt],
        request_s=np.asarray(request_s, float)[srt],
        origin=np.asarray(origin, np.int32)[srt],
        destination=np.asarray(destination, np.int32)[srt],
        patience_s=np.full(n, 90.0),
    )


def random_orders(rng: np.random.Generator, n: int, n_nodes: int, span_s: float) -> Orders:
    o = rng.integers(0, n_nodes, n)
    d = (o + rng.integers(1, n_nodes, n)) % n_nodes
    return make_orders(o, d, rng.uniform(0, span_s, n), rng.permutation(10 * n)[:n])


# ------------------------------------------------------------- the reference
def pool_scalar(dist, oa, da, ob, db, h, delta, pre, rules: PairRules):
    """§1.1 for one pair: None if infeasible, else (fofo, saving, L, det_a, det_b, shared, pk)."""
    la, lb, p = dist[oa, da], dist[ob, db], dist[h, ob]
    options = []
    for fofo in (True, False):
        if fofo:
            length = delta + p + dist[ob, da] + dist[da, db]
            ride_a, ride_b, shared = delta + p + dist[ob, da], dist[ob, da] + dist[da, db], dist[ob, da]
        else:
            length = delta + p + lb + dist[db, da]
            ride_a, ride_b, shared = length, lb, lb
        ok = ride_a - la <= rules.max_detour_m + TOL and ride_b - lb <= rules.max_detour_m + TOL
        options.append((ok, fofo, length, ride_a - la, ride_b - lb, shared))
    if rules.order_rule == "min_feasible":
        options = [x for x in options if x[0]]
        if not options:
            return None
        best = min(options, key=lambda x: (x[2], not x[1]))
    else:
        best = min(options, key=lambda x: (x[2], not x[1]))
        if not best[0]:
            return None
    pk = pre + p
    if rules.pickup_check and pk > rules.max_pickup_m + TOL:
        return None
    _, fofo, length, det_a, det_b, shared = best
    return fofo, la + lb - length, length, det_a, det_b, shared, pk


def arc_path(net, dist_oracle, o, d):
    """Nodes of the shortest path o->d and their cumulative arc lengths (summed arc by arc)."""
    nodes = dist_oracle.path_nodes(o, d)
    arcs = net.arc_index(nodes[:-1], nodes[1:])
    assert (arcs >= 0).all()
    return nodes, np.concatenate([[0.0], np.cumsum(net.arc_length_m[arcs])])


def brute_force(net, dist_oracle, orders: Orders, rules: PairRules) -> dict:
    dist = dist_oracle.dist
    out = {}
    for i, j in itertools.permutations(range(len(orders)), 2):
        if (orders.request_s[i], orders.order_id[i]) > (orders.request_s[j], orders.order_id[j]):
            continue  # i must be the earlier order (ties by id)
        oi, di, oj, dj = (
            int(x) for x in (orders.origin[i], orders.destination[i], orders.origin[j], orders.destination[j])
        )
        dt = orders.request_s[j] - orders.request_s[i]
        if dt <= rules.planner_patience_s:
            best = pool_scalar(dist, oi, di, oj, dj, oi, 0.0, 0.0, rules)
            row = None if best is None else (i, j, False) + best
            if rules.both_pickup_orders:
                rev = pool_scalar(dist, oj, dj, oi, di, oj, 0.0, 0.0, rules)
                if rev is not None and (best is None or rev[1] > best[1]):
                    row = (j, i, False) + rev
        elif rules.allow_enroute:
            s = rules.speed_mps * (dt - rules.planner_patience_s)
            if not 0 < s < dist[oi, di]:
                continue
            nodes, cum = arc_path(net, dist_oracle, oi, di)
            k = next(k for k in range(len(nodes)) if cum[k] >= s)
            res = pool_scalar(dist, oi, di, oj, dj, int(nodes[k]), cum[k], cum[k] - s, rules)
            row = None if res is None else (i, j, True) + res
        else:
            continue
        if row is not None:
            out[(min(i, j), max(i, j))] = row
    return out


def assert_same(cands, ref: dict):
    got = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(cands.low, cands.high, strict=True))}
    assert set(got) == set(ref)
    for key, k in got.items():
        first, second, enroute, fofo, saving, length, det_a, det_b, shared, pk = ref[key]
        assert (cands.first[k], cands.second[k], cands.enroute[k], cands.fofo[k]) == (first, second, enroute, fofo)
        np.testing.assert_allclose(
            [
                cands.saving_m[k],
                cands.length_m[k],
                cands.detour_first_m[k],
                cands.detour_second_m[k],
                cands.shared_m[k],
                cands.pickup_m[k],
            ],
            [saving, length, det_a, det_b, shared, pk],
            rtol=1e-9,
            atol=1e-6,
        )


FLAG_SETS = [
    dict(both_pickup_orders=b, pickup_check=p, allow_enroute=e)
    for b, p, e in itertools.product((False, True), repeat=3)
]


# ----------------------------------------------------------------- the tests
@pytest.mark.parametrize("flags", FLAG_SETS, ids=lambda f: "+".join(k for k, v in f.items() if v) or "default")
def test_enumeration_equals_brute_force(grid, flags):
    net, dist = grid
    orders = random_orders(np.random.default_rng(11), 45, net.n_nodes, span_s=600.0)
    rules = PairRules(max_detour_m=1500.0, max_pickup_m=1200.0, **flags)
    ref = brute_force(net, dist, orders, rules)
    cands = find_candidates(dist, orders, rules)
    assert len(ref) > 10  # the instance must have pairs to compare
    assert_same(cands, ref)
    if flags["allow_enroute"]:
        assert cands.enroute.any() and (~cands.enroute).any()


def test_enumeration_min_then_check_rule(grid):
    net, dist = grid
    orders = random_orders(np.random.default_rng(5), 40, net.n_nodes, span_s=400.0)
    rules = PairRules(max_detour_m=800.0, order_rule="min_then_check", allow_enroute=True)
    assert_same(find_candidates(dist, orders, rules), brute_force(net, dist, orders, rules))


@settings(max_examples=25, deadline=None, database=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(0, 14),
    span=st.sampled_from([0.0, 60.0, 200.0, 900.0]),
    detour=st.sampled_from([0.0, 700.0, 3000.0]),
    flags=st.sampled_from(FLAG_SETS),
)
def test_enumeration_property(grid, seed, n, span, detour, flags):
    net, dist = grid
    orders = random_orders(np.random.default_rng(seed), n, net.n_nodes, span_s=span)
    rules = PairRules(max_detour_m=detour, max_pickup_m=1000.0, **flags)
    assert_same(find_candidates(dist, orders, rules), brute_force(net, dist, orders, rules))


def test_blocks_do_not_change_the_result(grid):
    net, dist = grid
    orders = random_orders(np.random.default_rng(2), 120, net.n_nodes, span_s=900.0)
    rules = PairRules(allow_enroute=True, both_pickup_orders=True)
    whole = find_candidates(dist, orders, rules)
    tiny = find_candidates(dist, orders, rules, block_pairs=3)
    assert tiny.evaluated == whole.evaluated and len(whole) > 0
    for name in ("first", "second", "enroute", "fofo", "saving_m", "detour_first_m", "shared_m", "pickup_m"):
        np.testing.assert_array_equal(getattr(tiny, name), getattr(whole, name))


def test_time_window_is_inclusive_and_ties_go_by_id(grid):
    net, dist = grid
    # Same OD; orders 7 and 3 request at the same time, order 9 exactly K̄ later, order 1 just after.
    orders = make_orders([0, 0, 0, 0], [63, 63, 63, 63], [10.0, 10.0, 100.0, 100.0 + 1e-6], [7, 3, 9, 1])
    cands = find_candidates(dist, orders, PairRules(planner_patience_s=90.0))
    ids = {(int(orders.order_id[a]), int(orders.order_id[b])) for a, b in zip(cands.first, cands.second, strict=True)}
    assert (3, 7) in ids and (7, 3) not in ids  # the tie: smaller id picked up first
    assert (3, 9) in ids and (7, 9) in ids  # dt = K̄ exactly is allowed
    assert (3, 1) not in ids and (7, 1) not in ids
    assert (9, 1) in ids


def test_identical_orders_save_a_whole_trip(grid):
    net, dist = grid
    orders = make_orders([5, 5], [40, 40], [0.0, 0.0])
    cands = find_candidates(dist, orders, PairRules())
    assert len(cands) == 1
    assert cands.saving_m[0] == pytest.approx(dist.dist[5, 40])  # G3
    assert cands.detour_first_m[0] == pytest.approx(0) and cands.detour_second_m[0] == pytest.approx(0)


def test_pickup_is_not_tested_by_default(grid):
    net, dist = grid
    far = int(np.argmax(dist.dist[0]))
    orders = make_orders([0, far], [far, 0], [0.0, 1.0])
    assert not len(find_candidates(dist, orders, PairRules(max_detour_m=1e9, pickup_check=True, max_pickup_m=100.0)))
    assert len(find_candidates(dist, orders, PairRules(max_detour_m=1e9))) == 1


def test_enroute_boundaries(grid):
    """s exactly at a node of P_i turns there with pre = 0; s = l_i (i arrived) is no pair."""
    net, dist = grid
    o_i, d_i = 0, 63
    nodes = dist.path_nodes(o_i, d_i)
    k = len(nodes) // 2
    at_node = float(dist.dist[o_i, nodes[k]])
    l_i = float(dist.dist[o_i, d_i])
    # v = 1 m/s and K̄ = 0 make s = t_j - t_i exactly.
    rules = PairRules(planner_patience_s=0.0, speed_mps=1.0, max_detour_m=1e9, allow_enroute=True)
    orders = make_orders([o_i, 9, 9], [d_i, 60, 60], [0.0, at_node, l_i], [0, 1, 2])
    cands = find_candidates(dist, orders, rules)
    assert {(int(a), int(b)) for a, b in zip(cands.first, cands.second, strict=True)} == {(0, 1), (1, 2)}
    row = int(np.flatnonzero(cands.second == 1)[0])
    assert cands.enroute[row]
    assert cands.pickup_m[row] == pytest.approx(dist.dist[nodes[k], 9])  # pre = 0 at the node itself
    assert cands.length_m[row] >= at_node + dist.dist[nodes[k], 9]


def test_enroute_needs_the_distance_oracle(grid):
    net, dist = grid
    orders = make_orders([0, 1], [10, 11], [0.0, 200.0])
    with pytest.raises(ParameterError, match="Distances"):
        find_candidates(dist.dist, orders, PairRules(allow_enroute=True))
    assert len(find_candidates(dist.dist, orders, PairRules())) == 0  # a bare matrix is fine otherwise


@pytest.mark.parametrize(
    "bad",
    [dict(max_detour_m=-1.0), dict(planner_patience_s=float("nan")), dict(speed_mps=0.0), dict(order_rule="shortest")],
)
def test_bad_rules(bad):
    with pytest.raises(ParameterError):
        PairRules(**bad)
