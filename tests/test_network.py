"""Distance oracle: sanity of the all-pairs distances, paths, the disk cache, snapping."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.data import read_peak_orders, read_raw_peak_orders
from rpbench.exceptions import DataError, ParameterError
from rpbench.network import Distances, great_circle_m, snap
from rpbench.scenarios.common import haikou_network
from rpbench.scenarios.toy import grid_network


@pytest.fixture(scope="module")
def haikou(data_dir):
    return haikou_network(data_dir)


@pytest.fixture(scope="module")
def sample_pairs():
    rng = np.random.default_rng(42)
    return rng.integers(0, 3901, size=(3, 3000))


def test_two_way_network_is_symmetric(haikou, sample_pairs):
    d = haikou.distances().dist
    a, b, _ = sample_pairs
    assert np.allclose(d[a, b], d[b, a], rtol=0, atol=1e-6)
    assert (np.diag(d) == 0).all()


def test_triangle_inequality(haikou, sample_pairs):
    d = haikou.distances().dist
    a, b, c = sample_pairs
    assert (d[a, c] <= d[a, b] + d[b, c] + 1e-6).all()


def test_road_distance_at_least_great_circle(haikou, sample_pairs):
    d = haikou.distances().dist
    a, b, _ = sample_pairs
    gc = great_circle_m(haikou.lon[a], haikou.lat[a], haikou.lon[b], haikou.lat[b])
    # link lengths follow the road geometry, so they are never shorter than the chord (0.5 % slack for
    # the earth model used to measure the polylines)
    assert (d[a, b] >= 0.995 * gc - 1.0).all()


def test_paths_match_distances(haikou, sample_pairs):
    oracle = haikou.distances()
    a, b, _ = sample_pairs[:, :200]
    offsets, nodes = oracle.paths_batch(a, b)
    for i in range(200):
        path = nodes[offsets[i] : offsets[i + 1]]
        assert (path == oracle.path_nodes(a[i], b[i])).all()
        assert path[0] == a[i] and path[-1] == b[i]
        arcs = oracle.path_arcs(a[i], b[i])
        assert (arcs >= 0).all()
        assert haikou.arc_length_m[arcs].sum() == pytest.approx(oracle.dist[a[i], b[i]], abs=1e-6)


def test_cache_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path))
    net = grid_network(6)
    cold = Distances.load_or_build(net)
    assert not cold.from_cache
    warm = Distances.load_or_build(net)
    assert warm.from_cache
    assert np.array_equal(np.asarray(warm.dist), cold.dist) and np.array_equal(np.asarray(warm.pred), cold.pred)
    assert len(list(tmp_path.glob("apsp-*.npy"))) == 2


def test_unknown_node_id(haikou):
    with pytest.raises(DataError, match="node id 99999 is not a node"):
        haikou.index_of([1, 2, 99999])


def test_authors_snapping_rule_reproduces_their_nodes(data_dir, haikou):
    raw = read_raw_peak_orders(data_dir)
    snapped = read_peak_orders(data_dir, "2017-05-01").set_index("order_id")
    raw = raw[raw["order_id"].isin(snapped.index)]
    idx, dist_m = snap(haikou, raw["origin_lon"], raw["origin_lat"], rule="l1_degrees")
    same = haikou.node_id[idx] == snapped.loc[raw["order_id"], "origin_id"].to_numpy()
    assert same.mean() > 0.99
    near, near_m = snap(haikou, raw["origin_lon"], raw["origin_lat"], rule="nearest")
    assert (near_m <= dist_m + 1e-6).all()  # the true nearest node is never farther
    assert np.median(dist_m) < 400


def test_unknown_snapping_rule(haikou):
    with pytest.raises(ParameterError, match="unknown snapping rule"):
        snap(haikou, [110.3], [20.0], rule="closest")


@pytest.mark.parametrize("seed", range(5))
def test_arc_index_finds_each_arc_and_only_arcs(seed):
    net = grid_network(4)
    rng = np.random.default_rng(seed)
    tail, head = rng.integers(0, net.n_nodes, 40), rng.integers(0, net.n_nodes, 40)
    tail[:10], head[:10] = net.arc_tail[:10], net.arc_head[:10]  # some real arcs among them
    arcs = {(int(a), int(b)): i for i, (a, b) in enumerate(zip(net.arc_tail, net.arc_head, strict=True))}
    expected = [arcs.get((int(a), int(b)), -1) for a, b in zip(tail, head, strict=True)]
    assert net.arc_index(tail, head).tolist() == expected
    assert int(net.arc_index(int(tail[0]), int(head[0]))) == expected[0]
