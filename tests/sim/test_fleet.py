"""FleetState (rpbench.sim.fleet) on tiny hand-built networks with hand-computed times and odometers.

Vehicles drive at 10 m/s, so an arc of x metres takes x/10 seconds.  Node ids are 0..n-1, which are
also the internal node indices.  Networks:

* ``line``: ``line_network(6)`` — 0 - 1 - 2 - 3 - 4 - 5, 1000 m per arc (100 s).
* ``tee``::

      0 --400-- 1 --600-- 2 --500-- 3         plus a long road 0 -- 3 of 5000 m (never shortest)
                |
               300
                |
                4

* ``grid``: a 3 x 3 two-way grid, node r·3 + c, 1000 m arcs (every node has >= 2 neighbours).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers import line_network, network_from_edges

from rpbench.exceptions import ParameterError
from rpbench.sim.fleet import CRUISE_ARCS, DROPOFF, PICKUP, FleetState, Plan, Stop

SPEED = 10.0
BOUNCE = [0, 1, 2, 3, 4, 5, 4, 3, 2, 1]  # a cruise on the line from node 0: no U-turns except at the ends


@pytest.fixture(scope="module")
def line():
    return line_network(6, 1000.0)


@pytest.fixture(scope="module")
def tee():
    return network_from_edges([(0, 1, 400.0), (1, 2, 600.0), (2, 3, 500.0), (1, 4, 300.0), (0, 3, 5000.0)], name="tee")


@pytest.fixture(scope="module")
def grid():
    edges = [(r * 3 + c, r * 3 + c + 1, 1000.0) for r in range(3) for c in range(2)]
    edges += [(r * 3 + c, (r + 1) * 3 + c, 1000.0) for r in range(2) for c in range(3)]
    return network_from_edges(edges, name="grid")


def fleet(network, nodes, seed=0) -> FleetState:
    return FleetState(network, network.distances(), np.array(nodes), SPEED, np.random.default_rng(seed))


def assert_drivable(network, nodes, tt, odo):
    """Consecutive distinct nodes are joined by arcs, driven at SPEED; repeated nodes mean standing still."""
    assert (np.diff(tt) >= 0).all() and (np.diff(odo) >= 0).all()
    for i in range(len(nodes) - 1):
        if nodes[i] == nodes[i + 1]:
            assert odo[i + 1] == odo[i]
            continue
        arc = int(network.arc_index(nodes[i], nodes[i + 1]))
        assert arc >= 0, f"{nodes[i]} -> {nodes[i + 1]} is not an arc"
        assert odo[i + 1] - odo[i] == pytest.approx(network.arc_length_m[arc])
        assert tt[i + 1] - tt[i] == pytest.approx(network.arc_length_m[arc] / SPEED)


def test_new_fleet_stands_at_its_initial_nodes(line):
    fl = fleet(line, [2, 4])
    assert [p.nodes.tolist() for p in fl.plans] == [[2], [4]]
    assert [(p.tt.tolist(), p.odo.tolist()) for p in fl.plans] == [([0.0], [0.0]), ([0.0], [0.0])]
    k, node, pre = fl.positions(np.array([0, 1]), 500.0)
    assert k.tolist() == [0, 0] and node.tolist() == [2, 4] and pre.tolist() == [0.0, 0.0]


def test_route_through_and_replan_times(tee):
    fl = fleet(tee, [4])
    # 4 -> 0: 4-1-0 (300 + 400); 0 -> 3: 0-1-2-3 (400 + 600 + 500 = 1500 < the 5000 m road)
    tail, reach = fl.route_through([4, 0, 3])
    assert tail.tolist() == [1, 0, 1, 2, 3]
    assert reach == [2, 5]  # plan index of node 0 and of node 3
    # Stops come in any order and are sorted by plan index.
    fl.replan(0, 0, tail, [Stop(reach[1], DROPOFF, 7), Stop(reach[0], PICKUP, 7)])
    plan = fl.plans[0]
    assert plan.nodes.tolist() == [4, 1, 0, 1, 2, 3]
    # odometer: 0, +300, +400, +400, +600, +500;  time = odometer / 10 m/s
    assert plan.odo.tolist() == [0.0, 300.0, 700.0, 1100.0, 1700.0, 2200.0]
    assert plan.tt.tolist() == [0.0, 30.0, 70.0, 110.0, 170.0, 220.0]
    assert plan.stops == [Stop(2, PICKUP, 7), Stop(5, DROPOFF, 7)]
    assert not plan.cruising
    # A single waypoint is no route; same start and end gives an empty leg.
    tail, reach = fl.route_through([3])
    assert tail.tolist() == [] and reach == []
    tail, reach = fl.route_through([1, 1, 4])
    assert tail.tolist() == [4] and reach == [0, 1]


def test_stops_at_one_node_put_pickups_first(line):
    fl = fleet(line, [0])
    fl.replan(0, 0, np.array([1, 2]), [Stop(2, DROPOFF, 5), Stop(2, PICKUP, 6), Stop(1, DROPOFF, 4)])
    assert fl.plans[0].stops == [Stop(1, DROPOFF, 4), Stop(2, PICKUP, 6), Stop(2, DROPOFF, 5)]


@pytest.mark.parametrize(
    "t, k, node, pre",
    [
        (0.0, 0, 0, 0.0),  # at the start node
        (150.0, 2, 2, 500.0),  # half-way between node 1 (100 s) and node 2 (200 s): 50 s · 10 m/s before node 2
        (200.0, 2, 2, 0.0),  # exactly at node 2
        (420.0, 5, 5, 800.0),  # node 5 is reached at 500 s
        (600.0, 5, 5, 0.0),  # the route is over: standing at node 5
    ],
)
def test_position_along_a_route(line, t, k, node, pre):
    fl = fleet(line, [0, 3])
    tail, _ = fl.route_through([0, 5])
    fl.replan(0, 0, tail, [])  # node i at 100·i s, odometer 1000·i m
    assert fl.position(0, t) == (k, node, pytest.approx(pre))
    ks, nodes, pres = fl.positions(np.array([0, 1]), t)
    assert ks.tolist() == [k, 0] and nodes.tolist() == [node, 3]
    assert pres == pytest.approx([pre, 0.0])  # vehicle 1 never moves


def test_positions_over_successive_rounds(line):
    # The cached next node must follow the vehicle as time advances.
    fl = fleet(line, [0])
    fl.replan(0, 0, fl.route_through([0, 5])[0], [])
    expected = {
        10.0: (1, 1, 900.0),
        90.0: (1, 1, 100.0),
        100.0: (1, 1, 0.0),
        110.0: (2, 2, 900.0),
        350.0: (4, 4, 500.0),
        499.0: (5, 5, 10.0),
        700.0: (5, 5, 0.0),
        900.0: (5, 5, 0.0),
    }
    for t, (k, node, pre) in expected.items():
        ks, nodes, pres = fl.positions(np.array([0]), t)
        assert (int(ks[0]), int(nodes[0])) == (k, node), t
        assert float(pres[0]) == pytest.approx(pre), t


def test_next_odometers_follow_positions(line):
    # The odometer at the next plan node, cached with it: 1000 m per node on the line.
    fl = fleet(line, [0, 3])
    fl.replan(0, 0, fl.route_through([0, 5])[0], [])
    for t, odo in {0.0: 0.0, 150.0: 2000.0, 420.0: 5000.0, 900.0: 5000.0}.items():
        fl.positions(np.array([0, 1]), t)
        assert fl.next_odometers(np.array([0, 1])).tolist() == [odo, 0.0], t


def test_replan_at_an_anchor_keeps_the_history(tee):
    fl = fleet(tee, [4])
    tail, reach = fl.route_through([4, 0, 3])
    fl.replan(0, 0, tail, [Stop(reach[0], PICKUP, 7), Stop(reach[1], DROPOFF, 7)])
    # At 80 s the vehicle has left node 0 (70 s) and is 300 m before node 1 (index 3, 110 s).
    assert fl.position(0, 80.0) == (3, 1, pytest.approx(300.0))
    assert [s for s in fl.due_stops(80.0)] == [(70.0, 0, Stop(2, PICKUP, 7), 0, 700.0)]
    # Divert at node 1: collect order 8 at node 4, then drop both at node 3:  1-4 (300), 4-1 (300), 1-2-3 (1100).
    tail, reach = fl.route_through([1, 4, 3])
    assert tail.tolist() == [4, 1, 2, 3] and reach == [1, 4]
    fl.replan(0, 3, tail, [Stop(reach[0], PICKUP, 8), Stop(reach[1], DROPOFF, 7), Stop(reach[1], DROPOFF, 8)])
    old = fl.history[0][-1]
    assert old.nodes.tolist() == [4, 1, 0, 1]  # the old plan up to and including the anchor
    assert old.tt.tolist() == [0.0, 30.0, 70.0, 110.0]
    assert old.odo.tolist() == [0.0, 300.0, 700.0, 1100.0]
    plan = fl.plans[0]
    assert plan.nodes.tolist() == [1, 4, 1, 2, 3]
    assert plan.tt.tolist() == [110.0, 140.0, 170.0, 230.0, 280.0]
    assert plan.odo.tolist() == [1100.0, 1400.0, 1700.0, 2300.0, 2800.0]
    # Still 300 m before the anchor (now index 0 of the new plan).
    assert fl.position(0, 80.0) == (0, 1, pytest.approx(300.0))
    k, node, pre = fl.positions(np.array([0]), 80.0)
    assert (int(k[0]), int(node[0]), float(pre[0])) == (0, 1, pytest.approx(300.0))
    # The trajectory is history then plan, the anchor (node 1 at 110 s) once.
    nodes, tt, odo = fl.trajectory(0)
    assert nodes.tolist() == [4, 1, 0, 1, 4, 1, 2, 3]
    assert tt.tolist() == [0.0, 30.0, 70.0, 110.0, 140.0, 170.0, 230.0, 280.0]
    assert odo.tolist() == [0.0, 300.0, 700.0, 1100.0, 1400.0, 1700.0, 2300.0, 2800.0]
    assert_drivable(tee, nodes, tt, odo)
    # Up to 150 s: the nodes reached by then.
    nodes, tt, odo = fl.trajectory(0, t_end=150.0)
    assert nodes.tolist() == [4, 1, 0, 1, 4] and odo[-1] == 1400.0


def test_replan_past_an_unserved_stop_is_refused(tee):
    fl = fleet(tee, [4])
    tail, reach = fl.route_through([4, 0, 3])
    fl.replan(0, 0, tail, [Stop(reach[0], PICKUP, 7), Stop(reach[1], DROPOFF, 7)])
    with pytest.raises(RuntimeError, match="unserved stop"):
        fl.replan(0, 3, np.array([4]), [])  # the pick-up at index 2 has not been handled


def test_due_stops_in_time_order(line):
    fl = fleet(line, [0, 5])
    # vehicle 0: 0 -> 2 (pick-up order 1 at 200 s, 2000 m) -> 4 (drop-off at 400 s, 4000 m)
    tail, reach = fl.route_through([0, 2, 4])
    fl.replan(0, 0, tail, [Stop(reach[0], PICKUP, 1), Stop(reach[1], DROPOFF, 1)])
    # vehicle 1: 5 -> 4 (pick-up order 2 at 100 s, 1000 m) -> 1 (drop-off at 400 s, 4000 m)
    tail, reach = fl.route_through([5, 4, 1])
    fl.replan(1, 0, tail, [Stop(reach[0], PICKUP, 2), Stop(reach[1], DROPOFF, 2)])

    assert list(fl.due_stops(99.0)) == []
    # (time, vehicle, stop, node, odometer)
    assert list(fl.due_stops(250.0)) == [
        (100.0, 1, Stop(1, PICKUP, 2), 4, 1000.0),
        (200.0, 0, Stop(2, PICKUP, 1), 2, 2000.0),
    ]
    assert list(fl.due_stops(250.0)) == []  # each stop is produced once
    due = list(fl.due_stops(400.0))  # both at 400 s (inclusive): lower vehicle first
    assert due == [(400.0, 0, Stop(4, DROPOFF, 1), 4, 4000.0), (400.0, 1, Stop(4, DROPOFF, 2), 1, 4000.0)]
    assert fl.plans[0].stops == [] and fl.plans[1].stops == []


def test_due_stops_forget_replaced_plans(line):
    # A stop of a replaced plan is never produced; the new plan's stop is.
    fl = fleet(line, [0])
    fl.replan(0, 0, fl.route_through([0, 3])[0], [Stop(3, PICKUP, 1)])  # at node 3, 300 s
    fl.replan(0, 1, fl.route_through([1, 0])[0], [Stop(1, PICKUP, 2)])  # turn back at node 1: node 0 at 200 s
    assert list(fl.due_stops(1000.0)) == [(200.0, 0, Stop(1, PICKUP, 2), 0, 2000.0)]


def test_cruise_from_a_dead_end(line):
    fl = fleet(line, [0])
    fl.start_cruise(0, 0, t=50.0)
    plan = fl.plans[0]
    assert plan.cruising and plan.stops == []
    # The only way out of node 0 is 1; no U-turns until node 5 (a dead end), then back, and so on.
    assert len(plan.nodes) == CRUISE_ARCS + 1
    assert plan.nodes.tolist() == [BOUNCE[i % 10] for i in range(CRUISE_ARCS + 1)]
    # It waits at node 0 until 50 s, then drives 100 s per arc.
    assert plan.tt.tolist() == [50.0 + 100.0 * i for i in range(CRUISE_ARCS + 1)]
    assert plan.odo.tolist() == [1000.0 * i for i in range(CRUISE_ARCS + 1)]
    assert fl.position(0, 75.0) == (1, 1, pytest.approx(750.0))  # node 1 at 150 s
    # Past the 24 planned arcs (plan ends at 2450 s) the cruise is extended on demand:
    # at 2500 s the vehicle is heading to plan index 25 (2550 s), node BOUNCE[25 % 10] = 5, 500 m before it.
    assert fl.position(0, 2500.0) == (25, 5, pytest.approx(500.0))
    assert len(fl.plans[0].nodes) == 2 * CRUISE_ARCS + 1
    assert fl.plans[0].nodes.tolist() == [BOUNCE[i % 10] for i in range(2 * CRUISE_ARCS + 1)]
    # The standing time shows as node 0 twice (0 s and 50 s) in the trajectory.
    nodes, tt, odo = fl.trajectory(0)
    assert nodes[:3].tolist() == [0, 0, 1] and tt[:3].tolist() == [0.0, 50.0, 150.0]
    assert_drivable(line, nodes, tt, odo)


def test_random_walk_follows_arcs(grid):
    for seed in range(5):
        fl = fleet(grid, [4], seed=seed)
        walk = fl.random_walk_from(4, 1)  # at the centre, having come from node 1
        assert len(walk) == CRUISE_ARCS
        path = [1, 4] + walk.tolist()
        for a, b in itertools.pairwise(path):
            assert int(grid.arc_index(a, b)) >= 0
        # every grid node has >= 2 neighbours: never straight back
        assert all(path[i + 2] != path[i] for i in range(len(path) - 2))
    # The rng drives the choice: some seed leaves the centre other than straight on to 7.
    firsts = {int(fleet(grid, [4], seed=s).random_walk_from(4, 1)[0]) for s in range(20)}
    assert firsts <= {3, 5, 7} and len(firsts) > 1


def test_cruise_after_a_drop_off_on_the_grid(grid):
    fl = fleet(grid, [0], seed=3)
    tail, reach = fl.route_through([0, 2])  # 0 -> 1 -> 2, drop-off at node 2 (200 s)
    fl.replan(0, 0, tail, [Stop(reach[0], DROPOFF, 0)])
    [(_, _, stop, _, _)] = list(fl.due_stops(200.0))
    fl.start_cruise(0, stop.index)
    plan = fl.plans[0]
    assert plan.nodes[0] == 2 and plan.tt[0] == 200.0 and plan.odo[0] == 2000.0
    assert plan.nodes[1] == 5  # from the corner 2, not back to 1: only 5 is left
    fl.position(0, 200.0 + 100.0 * CRUISE_ARCS + 30.0)  # forces an extension
    nodes, tt, odo = fl.trajectory(0)
    assert nodes[:3].tolist() == [0, 1, 2]
    assert_drivable(grid, nodes, tt, odo)
    assert all(nodes[i + 2] != nodes[i] for i in range(len(nodes) - 2))


def test_park_stands_still(line):
    fl = fleet(line, [0])
    fl.start_cruise(0, 0)  # cruising 0 -> 1 -> 2 ... from 0 s
    k, node, pre = fl.position(0, 30.0)  # 700 m before node 1
    assert (k, node) == (1, 1) and pre == pytest.approx(700.0)
    fl.park(0, k)  # stop at node 1 (100 s, 1000 m)
    plan = fl.plans[0]
    assert plan.nodes.tolist() == [1] and plan.tt.tolist() == [100.0] and plan.odo.tolist() == [1000.0]
    assert not plan.cruising
    assert fl.position(0, 60.0) == (0, 1, pytest.approx(400.0))  # still driving in
    for t in (100.0, 1000.0, 1e5):
        assert fl.position(0, t) == (0, 1, 0.0)
        ks, nodes, pres = fl.positions(np.array([0]), t)
        assert (int(ks[0]), int(nodes[0]), float(pres[0])) == (0, 1, 0.0)
    nodes, tt, odo = fl.trajectory(0)
    assert nodes.tolist() == [0, 1] and tt.tolist() == [0.0, 100.0] and odo.tolist() == [0.0, 1000.0]


def test_plan_and_stop_records():
    plan = Plan(np.array([3], np.int32), np.array([5.0]), np.array([7.0]))
    assert plan.stops == [] and plan.cruising is False
    assert (PICKUP, DROPOFF) == (0, 1)
    assert Stop(2, PICKUP, 9) == Stop(index=2, kind=0, order=9)


def test_the_fleet_trajectories_are_each_vehicles_trajectory(tee):
    rng = np.random.default_rng(5)
    fl = fleet(tee, [4, 0, 2])
    for step in range(40):  # replans at random anchors, cruises and stops, as a run makes them
        v = int(rng.integers(0, 3))
        t = 10.0 * step
        k, h, _ = fl.positions(np.array([v]), t)
        if rng.random() < 0.5:
            fl.start_cruise(v, int(k[0]), t)
        else:
            tail, _ = fl.route_through([int(h[0]), int(rng.integers(0, 5))])
            fl.replan(v, int(k[0]), tail, [])
    for end in (None, 150.0, 1e9):
        offsets, nodes, tt, odo = fl.trajectories(end)
        for v in range(3):
            want = fl.trajectory(v, end)
            mine = slice(offsets[v], offsets[v + 1])
            got = (nodes[mine], tt[mine], odo[mine])
            for a, b in zip(got, want, strict=True):
                assert np.array_equal(a, b)


def test_replanning_many_vehicles_at_once_is_replanning_each(grid):
    rng = np.random.default_rng(9)
    for _ in range(30):
        one, many = fleet(grid, [0, 4, 8, 2], seed=3), fleet(grid, [0, 4, 8, 2], seed=3)
        t = float(rng.uniform(0.0, 200.0))
        vehicles = sorted(rng.choice(4, size=int(rng.integers(1, 5)), replace=False).tolist())
        ks, hs, _ = one.positions(np.array(vehicles), t)
        many.positions(np.array(vehicles), t)
        waypoints = [[int(h), *rng.integers(0, 9, size=int(rng.integers(1, 4))).tolist()] for h in hs.tolist()]

        def stops_of(i, reach, waypoints=waypoints):
            return [Stop(r, PICKUP if j % 2 == 0 else DROPOFF, 10 * i + j) for j, r in enumerate(reach)]

        for i, (v, k) in enumerate(zip(vehicles, ks.tolist(), strict=True)):
            tail, reach = one.route_through(waypoints[i])
            one.replan(v, k, tail, stops_of(i, reach))
        many.replan_through(vehicles, ks.tolist(), waypoints, stops_of)
        for v in range(4):
            a, b = one.plans[v], many.plans[v]
            assert a.nodes.tolist() == b.nodes.tolist() and a.tt.tolist() == b.tt.tolist()
            assert a.odo.tolist() == b.odo.tolist() and a.stops == b.stops and a.cruising == b.cruising
        for name in ("tt", "node", "odo", "base", "length", "tt_before", "last", "cruising"):
            assert np.array_equal(getattr(one._windows, name), getattr(many._windows, name)), name
        later = t + float(rng.uniform(0.0, 300.0))
        assert list(one.due_stops(later)) == list(many.due_stops(later))
        for v in range(4):
            for x, y in zip(one.trajectory(v), many.trajectory(v), strict=True):
                assert np.array_equal(x, y)


def test_replanning_many_vehicles_names_a_missing_path():
    one_way = network_from_edges([(0, 1, 100.0), (1, 2, 100.0), (2, 0, 100.0)], name="ring")
    d = one_way.distances()
    fl = FleetState(one_way, d, np.array([0, 1]), SPEED, np.random.default_rng(0))
    fl._pred = d.pred.copy()
    fl._pred[0, 2] = -1  # as if node 2 could not be reached from node 0
    with pytest.raises(ParameterError, match="no path from node 0 to node 2"):
        fl.replan_through([0, 1], [0, 0], [[0, 1], [1, 0, 2]], lambda i, reach: [])
    assert fl.plans[0].nodes.tolist() == [0] and fl.plans[1].nodes.tolist() == [1]  # nobody replanned


def _send_one_by_one(fl: FleetState, vehicles, targets, t: float) -> None:
    """:meth:`FleetState.send` spelt out per vehicle: position, shortest path, cruise on, replan."""
    anchors, starts, _ = fl.positions(np.asarray(vehicles), t)
    for v, k, h, node in zip(vehicles, anchors.tolist(), starts.tolist(), targets, strict=True):
        tail, _ = fl.route_through([h, node])
        walk = fl.random_walk_from(node, int(tail[-2]) if len(tail) > 1 else h)
        fl.replan(v, k, np.concatenate([tail, walk]), [], cruising=True)


def test_sending_vehicles_makes_the_plans_of_one_replan_each(grid):
    """Vehicles cruising, mid-arc or at a node, sent to a far node, a neighbour or where they are: the plans,
    windows and random numbers of one compiled call are those of a replan per vehicle."""
    vehicles, targets = [3, 0, 2, 1], [8, 1, 2, 4]  # 2 is sent to the node it stands at
    fleets = []
    for _ in range(2):
        fl = fleet(grid, [0, 1, 2, 4], seed=7)
        fl.on_duty[:] = True
        for v in (0, 1, 3):
            fl.start_cruise(v, 0)
        fleets.append(fl)
    t = 150.0  # the cruisers are mid-arc (arcs take 100 s)
    fleets[0].send(np.array(vehicles), np.array(targets), t)
    _send_one_by_one(fleets[1], vehicles, targets, t)
    sent, one_by_one = fleets
    for v in range(4):
        a, b = sent.plans[v], one_by_one.plans[v]
        assert a.nodes.tolist() == b.nodes.tolist() and a.cruising == b.cruising
        assert np.array_equal(a.tt, b.tt) and np.array_equal(a.odo, b.odo)
        for t_later in (t, 420.0, 900.0):  # the windows answer as the plans do
            assert [x.tolist() for x in sent.positions(np.array([v]), t_later)] == [
                x.tolist() for x in one_by_one.positions(np.array([v]), t_later)
            ]
    assert sent.rng.random() == one_by_one.rng.random()  # the same numbers were drawn
    assert sent.plans[2].nodes[0] == 2 and sent.plans[2].nodes[1] != 2  # sent where it stands: cruises on
