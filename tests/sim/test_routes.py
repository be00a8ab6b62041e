"""The compiled route kernels (rpbench.sim.routes) give exactly what the plain Python rules give.

The references below are the rules the kernels replaced, written out in Python: a cruise drawing
``int(u · len(candidates))`` among the outgoing heads without the previous node, the predecessor
chain of each shortest path, and times and odometers summed with ``np.cumsum``.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers import network_from_edges

from rpbench.exceptions import ParameterError
from rpbench.sim import routes
from rpbench.sim.fleet import FleetState


@pytest.fixture(scope="module")
def city():
    """A random strongly connected network: a two-way ring plus one-way chords, some dead-end spurs."""
    rng = np.random.default_rng(7)
    n = 40
    edges = [(i, (i + 1) % n, float(rng.integers(50, 400))) for i in range(n)]
    edges += [((i + 1) % n, i, float(rng.integers(50, 400))) for i in range(n)]
    for _ in range(60):
        a, b = (int(x) for x in rng.integers(0, n, 2))
        if a != b:
            edges.append((a, b, float(rng.integers(50, 900))))
    spurs = [(n + k, k * 5, 120.0) for k in range(4)] + [(k * 5, n + k, 120.0) for k in range(4)]
    return network_from_edges(edges + spurs, name="city")


def csr(network):
    heads = network.arc_head[network.out_arcs].astype(np.int64)
    return network.out_offsets.astype(np.int64), heads, network.arc_length_m[network.out_arcs].astype(np.float64)


def python_walk(network, node, prev, u):
    offsets, heads, _ = csr(network)
    out = []
    for x in u.tolist():
        succ = heads[offsets[node] : offsets[node + 1]].tolist()
        if len(succ) > 1 and prev >= 0:
            succ = [h for h in succ if h != prev] or succ
        nxt = succ[int(x * len(succ))]
        out.append(nxt)
        prev, node = node, nxt
    return out


def test_random_walk_matches_the_python_rule(city):
    offsets, heads, _ = csr(city)
    rng = np.random.default_rng(1)
    for _ in range(300):
        node = int(rng.integers(0, city.n_nodes))
        prev = int(rng.integers(-1, city.n_nodes))
        u = rng.random(30)
        assert routes.random_walk(offsets, heads, node, prev, u).tolist() == python_walk(city, node, prev, u)


def test_route_through_matches_path_nodes(city):
    d = city.distances()
    fl = FleetState(city, d, np.array([0]), 10.0, np.random.default_rng(0))
    rng = np.random.default_rng(2)
    for k in range(200):
        points = [int(x) for x in rng.integers(0, city.n_nodes, 2 + k % 4)]
        tail, reach = fl.route_through(points)
        want = [d.path_nodes(a, b)[1:].tolist() for a, b in itertools.pairwise(points)]
        assert tail.tolist() == list(itertools.chain(*want))
        assert reach == np.cumsum([len(w) for w in want]).tolist()


def test_route_through_without_a_path_names_it():
    one_way = network_from_edges([(0, 1, 100.0), (1, 2, 100.0), (2, 0, 100.0)], name="ring")
    d = one_way.distances()
    pred = d.pred.copy()
    pred[0, 2] = -1  # as if node 2 could not be reached from node 0
    fl = FleetState(one_way, d, np.array([0]), 10.0, np.random.default_rng(0))
    fl._pred = pred
    with pytest.raises(ParameterError, match="no path from node 0 to node 2"):
        fl.route_through([1, 0, 2])


def test_plan_times_and_odometers_match_cumsum(city):
    offsets, heads, lengths = csr(city)
    d = city.distances()
    rng = np.random.default_rng(3)
    for _ in range(100):
        a, b = (int(x) for x in rng.integers(0, city.n_nodes, 2))
        path = d.path_nodes(a, b)
        t0, odo0, speed = float(rng.random() * 1e4), float(rng.random() * 1e5), 25 / 3
        n = len(path)
        nodes, tt, odo = np.empty(n, np.int32), np.empty(n), np.empty(n)
        bad = routes.plan_arrays(offsets, heads, lengths, a, path[1:].astype(np.int64), t0, odo0, speed, nodes, tt, odo)
        cum = np.zeros(n)
        np.cumsum(city.arc_length_m[city.arc_index(path[:-1], path[1:])], out=cum[1:])
        assert bad == -1
        assert nodes.tolist() == path.tolist()
        assert tt.tolist() == (t0 + cum / speed).tolist() and odo.tolist() == (odo0 + cum).tolist()


def test_plan_refuses_nodes_not_joined_by_an_arc(city):
    fl = FleetState(city, city.distances(), np.array([0]), 10.0, np.random.default_rng(0))
    far = next(v for v in range(city.n_nodes) if int(city.arc_index(0, v)) < 0 and v != 0)
    with pytest.raises(ValueError, match=f"no arc from node 0 to node {far}"):
        fl.replan(0, 0, np.array([far]), [])
