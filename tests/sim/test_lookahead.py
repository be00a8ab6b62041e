"""Plan windows (rpbench.sim.lookahead) against a plain search of each plan, and the fleet's positions with them."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import network_from_edges

from rpbench.sim.fleet import FleetState
from rpbench.sim.lookahead import WIDTH, PlanWindows


def _plan(rng, length):
    """Nondecreasing times with repeats (standing still), nodes and odometers."""
    tt = np.cumsum(rng.choice([0.0, 5.0, 12.5, 30.0], length))
    return rng.integers(0, 50, length).astype(np.int32), tt, tt * 10.0


@pytest.mark.parametrize("seed", range(10))
def test_find_answers_as_searchsorted_or_declines(seed):
    rng = np.random.default_rng(seed)
    n = 12
    windows = PlanWindows(n)
    plans = [_plan(rng, int(rng.integers(1, 3 * WIDTH))) for _ in range(n)]
    for v, (nodes, tt, odo) in enumerate(plans):
        if v % 5 != 4:  # some vehicles have no window at all
            windows.fill(v, nodes, tt, odo, bool(v % 2), int(rng.integers(0, len(tt))))
    for before in rng.uniform(-10.0, 40.0 * WIDTH, 30):
        found = windows.find(np.arange(n), float(before))
        assert sorted(found.vehicles.tolist() + found.missed.tolist()) == list(range(n))
        for i, v in enumerate(found.vehicles.tolist()):
            nodes, tt, odo = plans[v]
            k = int(np.searchsorted(tt, before, side="left"))
            assert (found.k[i], found.node[i], found.tt[i], found.odo[i]) == (k, nodes[k], tt[k], odo[k])
            assert found.at_end[i] == (k == len(tt) - 1 and v % 2 == 0)
        for v in found.missed.tolist():  # declined only when the window cannot tell
            nodes, tt, odo = plans[v]
            k = int(np.searchsorted(tt, before, side="left"))
            inside = windows.length[v] > 0 and windows.base[v] <= k < windows.base[v] + windows.length[v]
            assert not inside


def test_a_dropped_window_answers_nothing():
    windows = PlanWindows(1)
    windows.fill(0, np.array([3, 4]), np.array([0.0, 10.0]), np.array([0.0, 100.0]), False, 0)
    assert windows.find(np.array([0]), 5.0).vehicles.tolist() == [0]
    windows.drop(0)
    assert windows.find(np.array([0]), 5.0).missed.tolist() == [0]


@pytest.mark.parametrize("seed", range(3))
def test_fleet_positions_match_each_plan_over_many_rounds(seed):
    # Cruising vehicles on a grid, some replanned now and then: positions() must equal the plan lookup.
    edges = [(r * 4 + c, r * 4 + c + 1, 90.0 + 7 * c) for r in range(4) for c in range(3)]
    edges += [(r * 4 + c, (r + 1) * 4 + c, 110.0 + 5 * r) for r in range(3) for c in range(4)]
    net = network_from_edges(edges, name="grid4")
    fl = FleetState(net, net.distances(), np.arange(6), 10.0, np.random.default_rng(seed))
    for v in range(6):
        fl.start_cruise(v, 0, 0.0)
    rng = np.random.default_rng(100 + seed)
    for t in np.arange(0.0, 2000.0, 10.0):
        if rng.random() < 0.2:
            v = int(rng.integers(0, 6))
            k = fl.position(v, t)[0]
            fl.replan(v, k, fl.route_through([int(fl.plans[v].nodes[k]), int(rng.integers(0, 16))])[0], [])
        ks, nodes, pres = fl.positions(np.arange(6), t)
        for v in range(6):
            k, node, pre = fl.position(v, t)
            assert (int(ks[v]), int(nodes[v])) == (k, node) and pres[v] == pytest.approx(pre)
            assert fl.next_odometers(np.array([v]))[0] == fl.plans[v].odo[k]
