"""Each switch of the authors' engine changes what it should, on cases small enough to check by hand.

Line networks have 1,000 m links; at the authors' 0.12 s/m a link takes 120 s.
"""

import numpy as np
import pandas as pd
import pytest
from helpers import line_network, scenario_of

from rpbench.backends.presets import load_preset
from rpbench.data.road import NetworkTables
from rpbench.exceptions import ParameterError
from rpbench.harness.replicate import Inputs, run_authors
from rpbench.network import RoadNetwork
from rpbench.replication import weights
from rpbench.replication.cells import NO_CELL, node_cells
from rpbench.replication.engine import AuthorsEngine, Leg, Vehicle
from rpbench.replication.switches import NAMES, Switches, ablation_steps, steps_for
from rpbench.scenarios.paper_input import PaperInput

PRESET = load_preset("highs")


def engine(scenario, strategy="mb", **off) -> AuthorsEngine:
    switches = Switches().without(*[k for k, v in off.items() if v is False])
    return AuthorsEngine(scenario, strategy, PRESET, switches=switches)


def served(outcome) -> set[int]:
    return {int(outcome.scenario_orders.order_id[r.order]) for r in outcome.records}


# ---------------------------------------------------------------- the switch set
def test_all_on_is_the_authors_and_the_ablation_is_one_off_at_a_time():
    assert Switches().off() == [] and Switches().label() == "authors"
    assert Switches.none().off() == list(NAMES)
    steps = ablation_steps()
    assert [name for name, _ in steps] == ["authors"] + [f"no-{n}" for n in NAMES] + ["all-off"]
    assert all(len(sw.off()) == 1 for _, sw in steps[1:-1])
    cumulative = steps_for("cumulative")
    assert [len(sw.off()) for _, sw in cumulative] == list(range(len(NAMES) + 1))  # 1..k off, k = 0..8
    assert cumulative[-1][1] == Switches.none()
    with pytest.raises(ParameterError, match="--ablation 'some'"):
        steps_for("some")
    with pytest.raises(ParameterError, match="unknown mechanism 'warp'"):
        Switches().without("warp")


# ---------------------------------------------------------------- 1 teleport
def _taker(eng, vehicle_node, order, t_assign=0.0):
    veh = eng.vehicles[0]
    veh.node, veh.passenger, veh.picked_up = vehicle_node, order, False
    veh.assigned_s, veh.assign_node = t_assign, vehicle_node
    veh.active_at = t_assign
    return veh


def test_teleport_jumps_to_the_last_node_of_the_route_in_one_round():
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 3, 6)], [0])
    eng = engine(sc)
    veh = _taker(eng, net.index_of([0])[0], 0)
    eng._move_taker(0, veh, 130.0)  # 130 s > 120 s for the first link
    assert veh.node == net.index_of([3])[0]  # 3,000 m in one step
    assert veh.pickup_m == 1000.0  # MB's ledger keeps only the last link


def test_without_teleport_the_vehicle_is_where_the_clock_says():
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 3, 6)], [0])
    eng = engine(sc, teleport=False)
    leg = eng._leg(0.0, [int(net.index_of([0])[0]), int(net.index_of([3])[0])])
    assert isinstance(leg, Leg)
    assert leg.node_at(130.0) == net.index_of([1])[0]  # one link after 120 s
    assert leg.node_at(359.0) == net.index_of([2])[0]
    assert leg.end_s == pytest.approx(360.0)


# ---------------------------------------------------------------- 2 early release
@pytest.mark.parametrize("early, vacant_at", [(True, 300.0), (False, 0.12 * (1000 + 3000))])
def test_early_release_frees_a_solo_vehicle_before_its_real_arrival(early, vacant_at):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 1, 4)], [0])
    eng = engine(sc, early_release=early)
    veh = _taker(eng, net.index_of([4])[0], 0)  # it has already jumped to the destination
    veh.picked_up, veh.assign_node = True, int(net.index_of([0])[0])  # assigned at node 0 at t = 0
    eng._move_taker(0, veh, 300.0)  # at the destination: delivered this batch
    assert veh.passenger == -1
    assert veh.active_at == pytest.approx(vacant_at)


# ---------------------------------------------------------------- 3 grid cells
def _four_node_network() -> RoadNetwork:
    # Node 0 comes first so the authors' min/max scan finds the true minimum (see cells.py).
    ids = np.array([0, 1, 2, 3])
    a, b = np.array([0, 1, 2]), np.array([3, 2, 3])
    tables = NetworkTables(
        name="cells",
        node_id=ids,
        lon=np.array([110.09, 110.00, 110.01, 110.06]),
        lat=np.array([20.02, 20.00, 20.01, 20.01]),
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.full(6, 1000.0),
        arc_link_id=np.arange(6),
        source="tests",
    )
    return RoadNetwork.from_tables(tables)


def test_cells_follow_the_authors_grid():
    net = _four_node_network()
    cells = node_cells(net.lon, net.lat)
    assert cells[1] == NO_CELL  # on the grid's edge: in no cell
    assert cells[2] != cells[3] and cells[0] == cells[3]


@pytest.mark.parametrize("cells, expected", [(True, set()), (False, {0})])
def test_grid_cells_hide_a_vehicle_in_the_next_cell(cells, expected):
    net = _four_node_network()
    sc = scenario_of(net, [(5.0, 2, 1)], [3])  # vehicle 1,000 m away, but in another cell
    out = engine(sc, grid_cells=cells).run()
    # Assigned, not served: with no later passenger the authors' loop never moves the vehicle again.
    assert {order for order, _v, _t in out.assigned} == expected


# ---------------------------------------------------------------- 4 pick-up from the first origin
@pytest.mark.parametrize("first_origin, lead, saving", [(True, 1000.0, 5000.0), (False, 3000.0, 3000.0)])
def test_second_pickup_measured_from_the_first_origin(first_origin, lead, saving):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 0, 6), (6.0, 1, 6)], [2])
    eng = engine(sc, pickup_from_first_origin=first_origin)
    veh = _taker(eng, net.index_of([2])[0], 0)
    veh.picked_up = True  # the first passenger boarded at node 0 and rode to node 2
    g = eng._taker_geometry(veh, np.array([1])).first()
    assert g.lead_m == lead  # from O_a: 1,000 m; from the vehicle: 2,000 + 1,000 m
    assert g.saving_m == saving


# ---------------------------------------------------------------- 5 idle jumps
@pytest.mark.parametrize("jumps, moved", [(True, True), (False, False)])
def test_idle_vehicles_jump_to_order_origins(jumps, moved):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 5, 6)], [0])
    eng = engine(sc, idle_jumps=jumps)
    veh: Vehicle = eng.vehicles[0]
    eng._idle(veh, 10.0)  # picks a random order origin (the only one: node 5)
    eng._idle(veh, 1000.0)  # first link's time has passed: the jump
    assert bool(veh.node == net.index_of([5])[0]) is moved


# ---------------------------------------------------------------- 6 the authors' input
def test_authors_input_switch_chooses_the_input():
    net = line_network(4)
    paper = PaperInput(scenario_of(net, [(5.0, 0, 3)], [1]), predictions=None, response_denominator=7)
    peak = PaperInput(scenario_of(net, [(5.0, 0, 3)], [1]), predictions=None, response_denominator=1)
    inputs = Inputs(paper=paper, peak=peak)
    assert run_authors(inputs, "mb", Switches(), PRESET).denominator == 7
    assert run_authors(inputs, "mb", Switches().without("authors_input"), PRESET).denominator == 1


# ---------------------------------------------------------------- 7 weights and small rules
def test_authors_np_prefers_the_long_trip_rpbench_np_the_near_one():
    net = line_network(8)
    # Vehicle at node 2: A (1,000 m away, 1,000 m ride) and B (2,000 m away, 3,000 m ride) request together.
    sc = scenario_of(net, [(5.0, 3, 4), (5.0, 0, 3)], [2])
    # (grid cells off: the line's nodes share one latitude, so the authors' grid has no cell at all)
    authors = engine(sc, "np", grid_cells=False).run()
    rpbench = engine(sc, "np", authors_weights=False, grid_cells=False).run()
    assert served(authors) == {1}  # (3000 - 2000) + 3000 beats (1000 - 1000) + 3000
    assert served(rpbench) == {0}  # -1000 beats -2000


def test_weight_formulas():
    pk, ride, e, prio = np.array([500.0]), np.array([2000.0]), np.array([800.0]), np.array([1.0])
    rules = weights.RULES
    assert weights.vacant_values(rules["mb"], True, pk, ride, e, prio)[0] == 2500.0
    assert weights.vacant_values(rules["mb"], False, pk, ride, e, prio)[0] == -500.0
    assert weights.vacant_values(rules["np"], True, pk, ride, e, prio)[0] == 4500.0  # (ride - pk) + 3000
    assert weights.vacant_values(rules["np"], False, pk, ride, e, prio)[0] == -500.0
    assert weights.vacant_values(rules["fl-nd"], True, pk, ride, e, prio)[0] == 3300.0
    assert weights.vacant_values(rules["fl-nd"], False, pk, ride, e, prio)[0] == 300.0
    assert weights.vacant_values(rules["fl"], True, pk, ride, e, prio)[0] == pytest.approx(800.0**2 / 1300.0)
    assert weights.taker_values(rules["mb"], True, e, pk, prio)[0] == 3300.0
    assert weights.taker_values(rules["fl"], False, e, pk, prio)[0] == pytest.approx(800.0**2 / 1300.0)
    offsets = {name: weights.offset(r, True) for name, r in rules.items() if not r.packs_trips}
    assert offsets == {"np": 2000.0, "mb": 1000.0, "fl-nd": 2000.0, "fl": 0.0}
    assert all(weights.offset(r, False) == 0.0 for r in rules.values())
    assert weights.balanced(np.array([0.0]), np.array([0.0]))[0] == 0.0


def test_patience_floor_only_off_the_authors_mb():
    net = line_network(4)
    sc = scenario_of(net, [(5.0, 0, 3)], [1], patience_s=20.0)
    assert engine(sc).patience_s[0] == 20.0
    assert engine(sc, authors_weights=False).patience_s[0] == 30.0
    assert engine(sc, "rtv").patience_s[0] == 30.0


# ---------------------------------------------------------------- per-strategy rules
@pytest.mark.parametrize("strategy, idles", [("np", True), ("mb", False)])
def test_early_return_batches_move_nobody(strategy, idles):
    net = line_network(7)
    sc = scenario_of(net, [(1000.0, 5, 6)], [0], horizon_s=500.0)  # the horizon ends before the request
    called = []

    class Counting(AuthorsEngine):
        def _idle(self, veh, t):
            called.append(t)
            super()._idle(veh, t)

    assert Counting(sc, strategy, PRESET).rules.early_return is not idles
    Counting(sc, strategy, PRESET).run()
    # Without passengers the authors' MB returns before moving anyone; their NP moves its idle vehicles.
    assert bool(called) is idles


@pytest.mark.parametrize("ledger, scale", [(True, 2.0), (False, 1.0)])
def test_predictions_are_doubled_under_the_authors_ledger(ledger, scale):
    net = line_network(4)
    sc = scenario_of(net, [(5.0, 0, 3)], [1])
    predictions = pd.DataFrame({"saved_distance_for_seeker": [100.0], "saved_distance_for_taker": [40.0]})
    eng = AuthorsEngine(
        sc, "fl", PRESET, switches=Switches().without(*([] if ledger else ["authors_ledger"])), predictions=predictions
    )
    assert eng.fl_params.double_predictions is ledger
    assert eng.seeker_saving_m[0] == scale * 100.0 and eng.taker_saving_m[0] == scale * 40.0
    # MB reads no predictions; FL without them is one clear error.
    assert AuthorsEngine(sc, "mb", PRESET).taker_saving_m[0] == 0.0
    with pytest.raises(ParameterError, match="needs the per-order predictions"):
        AuthorsEngine(sc, "fl", PRESET)


# ---------------------------------------------------------------- 8 ledger and parameters
@pytest.mark.parametrize("ledger, counted", [(True, False), (False, True)])
def test_a_solo_passenger_counts_as_served_only_once_delivered(ledger, counted):
    net = line_network(7)
    # One order at 08:59:45; the hour ends before the vehicle can deliver it.
    sc = scenario_of(net, [(3585.0, 1, 6)], [0])
    out = engine(sc, authors_ledger=ledger, grid_cells=False).run()
    assert (len(out.records) == 1) is counted


def test_fl_parameters_follow_the_ledger_switch():
    assert weights.fl_params(True).alpha == 1.1 and weights.fl_params(True).response_rate == 0.8
    assert weights.fl_params(False).alpha == 1.01 and weights.fl_params(False).response_rate == 0.75
    k = np.array([1.0])
    fl = weights.RULES["fl"]
    doubled = weights.wait_values(fl, True, np.array([100.0]), k, weights.fl_params(True))[0]
    plain = weights.wait_values(fl, True, np.array([100.0]), k, weights.fl_params(False))[0]
    assert doubled == pytest.approx(100 * (1 - 0.2**8) / 2)  # times 1/(k+1)
    assert plain == pytest.approx(100 * (1 - 0.25**8))


# ---------------------------------------------------------------- RTV
def test_rtv_packs_two_passengers_only_when_vehicles_are_scarce():
    net = line_network(8)
    # Two passengers from node 1 (to nodes 6 and 4; the pair saves 3,000 m) and one vehicle at node 0:
    # the pair (worth its saving, 3,000) beats one solo trip (3,000 - 1,000).
    sc = scenario_of(net, [(5.0, 1, 6), (5.0, 1, 4)], [0])
    out = engine(sc, "rtv").run()
    assert len(out.records) == 2 and all(r.pooled for r in out.records)
    # With two vehicles the authors' values prefer two solo trips (2,000 + 2,000) to the pair (3,000).
    sc2 = scenario_of(net, [(5.0, 1, 6), (5.0, 1, 4)], [0, 0])
    out2 = engine(sc2, "rtv").run()
    assert not any(r.pooled for r in out2.records if r.assign_s == 10.0)
