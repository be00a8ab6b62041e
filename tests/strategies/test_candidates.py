"""Feasible options of a round (rpbench.strategies.candidates) and the node-pair table that pre-filters them."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers import line_network, network_from_edges, round_state

from rpbench.geometry import TOLERANCE_M, choose_order, pair_geometry
from rpbench.scenarios.base import Params
from rpbench.strategies.candidates import NearTable, join_options, near_table, vacant_options


@pytest.mark.parametrize("seed", range(10))
def test_mask_matches_the_distance_test(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 20))
    dist = rng.integers(0, 10, size=(n, n)).astype(float)
    dist[rng.random((n, n)) < 0.1] = np.inf  # unreachable pairs
    frm, to = rng.integers(0, n, int(rng.integers(0, 12))), rng.integers(0, n, int(rng.integers(0, 12)))
    table = NearTable.build(dist, 5.0)  # 5.0 itself is within (<=)
    assert np.array_equal(table.mask(frm, to), dist[frm[None, :], to[:, None]] <= 5.0)


def test_the_table_is_kept_for_the_same_array_and_threshold():
    dist = np.zeros((3, 3))
    first = near_table(dist, 1.0)
    assert near_table(dist, 1.0) is first
    assert near_table(dist, 2.0) is not first and near_table(dist.copy(), 2.0).dist is not dist


def _grid(size=5, length=400.0):
    edges = [(r * size + c, r * size + c + 1, length + 37.0 * c) for r in range(size) for c in range(size - 1)]
    edges += [(r * size + c, (r + 1) * size + c, length + 11.0 * r) for r in range(size - 1) for c in range(size)]
    return network_from_edges(edges, name="grid")


def _reference_vacant(state):
    """The exhaustive search: every (passenger, vacant vehicle) pair within R̄."""
    pk = state.v0_pre_m[None, :] + state.dist[state.v0_node[None, :], state.p_origin[:, None]]
    p, v = np.nonzero(pk <= state.params.max_pickup_m + TOLERANCE_M)
    return p, v, pk[p, v]


def _reference_join(state):
    """The exhaustive search: every (passenger, occupied vehicle) pair, R̄ first, then POOL."""
    p, v = (a.ravel() for a in np.meshgrid(np.arange(state.n_passengers), np.arange(state.n_v1), indexing="ij"))
    pk = state.v1_pre_m[v] + state.dist[state.v1_node[v], state.p_origin[p]]
    near = pk <= state.params.max_pickup_m + TOLERANCE_M
    p, v = p[near], v[near]
    g = pair_geometry(
        state.dist,
        state.v1_origin[v],
        state.v1_destination[v],
        state.v1_solo_m[v],
        state.p_origin[p],
        state.p_destination[p],
        state.p_solo_m[p],
        state.v1_node[v],
        state.v1_delta_m[v],
        state.v1_pre_m[v],
        state.params.max_detour_m,
    )
    r = choose_order(g, state.params.max_pickup_m, "min_feasible")
    return p[r.feasible], v[r.feasible], r.pk[r.feasible], r.saving[r.feasible]


@pytest.mark.parametrize("seed", range(12))
def test_candidates_equal_the_exhaustive_search(seed):
    rng = np.random.default_rng(seed)
    net = _grid()
    nodes = net.node_id

    def pick(k):
        return rng.choice(nodes, k).tolist()

    passengers = list(zip(pick(8), pick(8), strict=True))
    vacant = [(node, float(pre)) for node, pre in zip(pick(6), rng.choice([0.0, 150.0, 399.5], 6), strict=True)]
    occupied = [
        {
            "node": a,
            "origin": b,
            "destination": c,
            "delta": float(rng.integers(0, 300)),
            "pre": float(rng.choice([0.0, 200.0])),
            "onboard": bool(rng.random() < 0.5),
        }
        for a, b, c in zip(pick(5), pick(5), pick(5), strict=True)
    ]
    params = Params(max_pickup_m=float(rng.choice([400.0, 800.0, 1600.0])), max_detour_m=900.0)
    state = round_state(net, passengers, vacant, occupied=occupied, params=params)
    vac = vacant_options(state)
    p, v, pk = _reference_vacant(state)
    assert np.array_equal(vac.p, p) and np.array_equal(vac.v, v) and np.array_equal(vac.pickup_m, pk)
    join = join_options(state)
    p, v, pk, saving = _reference_join(state)
    assert np.array_equal(join.p, p) and np.array_equal(join.v, v)
    assert np.array_equal(join.pickup_m, pk) and np.array_equal(join.saving_m, saving)


def test_a_negative_lead_distance_searches_every_pair():
    # pre < 0 is outside the simulator's states; the filter must then not drop anything.
    net = _grid()
    state = round_state(
        net, [(net.node_id[0], net.node_id[24])], [(net.node_id[24], 0.0)], params=Params(max_pickup_m=500.0)
    )
    state = replace(state, v0_pre_m=np.array([-5000.0]))
    vac = vacant_options(state)
    p, v, pk = _reference_vacant(state)
    assert np.array_equal(vac.p, p) and np.array_equal(vac.v, v) and np.array_equal(vac.pickup_m, pk)
    assert len(p) == 1


def test_the_compiled_columns_are_the_numpy_columns_in_any_option_order():
    from rpbench.strategies.candidates import JoinOptions, VacantOptions, _ordered_columns, _ordered_columns_numpy

    rng = np.random.default_rng(9)
    net = line_network(6)
    for _ in range(200):
        n_p, n_v0, n_v1 = int(rng.integers(0, 5)), int(rng.integers(0, 4)), int(rng.integers(0, 3))
        state = round_state(
            net,
            [(0, 5)] * n_p,
            [(int(rng.integers(0, 6)), 0.0) for _ in range(n_v0)],
            occupied=[{"node": 3, "origin": 3, "destination": 5} for _ in range(n_v1)],
        )
        state = replace(
            state,
            p_order=rng.permutation(100)[:n_p],
            v0_vehicle=rng.permutation(50)[:n_v0],
            v1_vehicle=50 + rng.permutation(50)[:n_v1],
        )
        vac_pairs = [(p, v) for p in range(n_p) for v in range(n_v0) if rng.random() < 0.7]
        join_pairs = [(p, v) for p in range(n_p) for v in range(n_v1) if rng.random() < 0.7]
        rng.shuffle(vac_pairs), rng.shuffle(join_pairs)  # any order: the columns are sorted all the same
        vp = np.array([q[0] for q in vac_pairs], np.int64)
        vv = np.array([q[1] for q in vac_pairs], np.int64)
        jp = np.array([q[0] for q in join_pairs], np.int64)
        jv = np.array([q[1] for q in join_pairs], np.int64)
        vac = VacantOptions(vp, vv, rng.random(len(vp)) * 3000)
        nj = len(jp)
        join = JoinOptions(jp, jv, rng.random(nj) * 3000, rng.random(nj) * 900, rng.random(nj) < 0.5, rng.random(nj))
        utilities = (-rng.integers(0, 3, len(vp)) * 1.0, rng.integers(0, 3, nj) * 1.0, np.full(n_p, -7.0))
        got = _ordered_columns(state, vac, utilities[0], join, utilities[1], utilities[2])
        want = _ordered_columns_numpy(state, vac, utilities[0], join, utilities[1], utilities[2])
        assert got is not None and len(got) == len(want)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == w.dtype
            np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("rule", ["min_feasible", "min_then_check"])
def test_the_compiled_join_options_are_the_numpy_ones(rule):
    from rpbench.strategies.candidates import _join_options_numpy

    rng = np.random.default_rng(21)
    n = 30
    edges = [(i, (i + 1) % n, float(rng.integers(100, 900))) for i in range(n)]
    edges += [((i + 1) % n, i, float(rng.integers(100, 900))) for i in range(n)]
    edges += [(int(a), int(b), float(rng.integers(200, 3000))) for a, b in rng.integers(0, n, (40, 2)) if a != b]
    net = network_from_edges(edges, name="ring")
    params = Params(max_pickup_m=2500.0, max_detour_m=1500.0)
    found = 0
    for _ in range(60):
        passengers = [tuple(int(x) for x in rng.integers(0, n, 2)) for _ in range(int(rng.integers(1, 8)))]
        occupied = [
            {
                "node": int(rng.integers(0, n)),
                "origin": int(rng.integers(0, n)),
                "destination": int(rng.integers(0, n)),
                "delta": float(rng.random() * 800),
                "pre": float(rng.random() * 300) * int(rng.integers(0, 2)),
                "onboard": bool(rng.random() < 0.5),
            }
            for _ in range(int(rng.integers(1, 6)))
        ]
        state = round_state(net, passengers, [], params=params, occupied=occupied)
        got, want = join_options(state, rule), _join_options_numpy(state, rule)
        for name in ("p", "v", "pickup_m", "saving_m", "fofo", "remaining_m"):
            g, w = getattr(got, name), getattr(want, name)
            assert g.dtype == w.dtype and g.tolist() == w.tolist(), name
        found += len(got.p)
    assert found > 20
