"""Details of the authors' loop that decide whether the engine follows their published code batch by batch.

Compared batch by batch with the authors' published RTV code on 2017-05-02
(docs/replication.md), the engine's state depends on the order in which a batch's new
passengers are listed, the list idle vehicles draw targets from, and a vehicle assigned
while already standing at its passenger's origin.  In the loop MB shares with NP and FL
(their ``baseline2_batch_matching``), it also depends on how an idle vehicle moves, and on
the same vehicle-at-origin rule.  Line networks have 1,000 m links (120 s each at the
authors' 0.12 s/m).
"""

import random

import numpy as np
import pytest
from helpers import line_network, scenario_of

from rpbench.backends.presets import load_preset
from rpbench.replication.engine import AuthorsEngine
from rpbench.replication.rtv import build_round
from rpbench.scenarios.paper_input import load_paper_input

PRESET = load_preset("highs")


class _Recording(AuthorsEngine):
    """Keeps the passenger list each RTV batch was built from."""

    def _match_rtv(self, t, seekers, active):
        self.rounds = getattr(self, "rounds", []) + [(t, list(seekers))]
        return super()._match_rtv(t, seekers, active)


def test_a_batchs_new_passengers_follow_the_release_rank():
    net = line_network(8)
    sc = scenario_of(net, [(5.0, 1, 6), (6.0, 2, 4)], [0])
    by_time = _Recording(sc, "rtv", PRESET)
    by_time.run()
    by_rank = _Recording(sc, "rtv", PRESET, release_rank=np.array([1, 0]))
    by_rank.run()
    assert by_time.rounds[0] == (10.0, [0, 1])
    assert by_rank.rounds[0] == (10.0, [1, 0])  # the authors' sample order, not the request time


def test_the_listing_order_decides_an_rtv_pair_value():
    # A: 1 -> 6 (5,000 m), B: 2 -> 4 (2,000 m).  The authors' pair edge takes the later-listed passenger as
    # the first one, its pick-up of the other counted as its ride: A first saves 2,000 m, B first 1,000 m.
    net = line_network(8)
    sc = scenario_of(net, [(5.0, 1, 6), (6.0, 2, 4)], [3])
    eng = AuthorsEngine(sc, "rtv", PRESET)

    def pair_value(seekers):
        model, decode = build_round(eng, 10.0, seekers, [0])
        return [model.values[c] / 1000 for c, (_v, trip) in enumerate(decode) if len(trip) == 2]

    assert pair_value([1, 0]) == [2000.0]
    assert pair_value([0, 1]) == [1000.0]


def test_idle_vehicles_draw_from_the_given_origins():
    net = line_network(8)
    sc = scenario_of(net, [(5.0, 5, 6)], [0])
    origins = net.index_of([7])
    eng = AuthorsEngine(sc, "rtv", PRESET, reposition_origins=origins)
    veh = eng.vehicles[0]
    eng._idle(veh, 1000.0)
    assert veh.node == origins[0]  # not the released orders' origin (node 5)


@pytest.mark.parametrize(
    "start, picked, active_at, node",
    [
        (1, True, 0.0, 1),  # at the origin: picked up at once, activity time kept
        (0, False, 130.0, 1),  # one link away, 130 s > 120 s since it was last active: jumps, reset to now
    ],
)
def test_rtv_vehicle_assigned_at_the_origin_counts_as_picked_up(start, picked, active_at, node):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 1, 5)], [start])
    eng = AuthorsEngine(sc, "rtv", PRESET)
    veh = eng.vehicles[0]
    eng._apply(130.0, {0: (0,)}, [0])
    assert veh.passenger == 0 and veh.picked_up is picked
    assert veh.active_at == active_at
    assert veh.node == net.index_of([node])[0]


def test_the_paper_input_carries_sample_order_and_idle_origins(data_dir):
    paper = load_paper_input(data_dir, date="2017-05-02")
    orders = paper.scenario.orders
    assert len(paper.idle_origins) == 477  # distinct origins of all 928 sampled orders
    # The fleet is placed on the same list (random.seed(i); random.choice(origins)).
    placed = [random.Random(i).choice(list(paper.idle_origins)) for i in range(len(paper.scenario.fleet))]
    assert np.array_equal(paper.scenario.fleet.initial_node, placed)
    rank = paper.sample_rank
    assert len(rank) == len(orders) and len(np.unique(rank)) == len(rank) and rank.max() < 928
    assert not np.all(np.diff(rank) > 0)  # sample order is not request-time order


def test_run_authors_passes_the_inputs_order_and_origins(monkeypatch):
    from rpbench.harness import replicate as runner
    from rpbench.harness.replicate import Inputs, run_authors
    from rpbench.replication.switches import Switches
    from rpbench.scenarios.paper_input import PaperInput

    seen = {}

    class Capture(AuthorsEngine):
        def __init__(self, *args, **kwargs):
            seen.update(kwargs)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(runner, "AuthorsEngine", Capture)
    net = line_network(4)
    paper = PaperInput(
        scenario_of(net, [(5.0, 0, 3)], [1]),
        predictions=None,
        response_denominator=7,
        sample_rank=np.array([4]),
        idle_origins=net.index_of([2]),
    )
    run_authors(Inputs(paper=paper, peak=paper), "rtv", Switches(), PRESET)
    assert list(seen["release_rank"]) == [4] and list(seen["reposition_origins"]) == list(net.index_of([2]))


@pytest.mark.parametrize(
    "start, picked, node_next",
    [
        (1, True, 5),  # at the origin: picked up at once, so the next batch already delivers
        (0, False, 1),  # one link away: the next batch jumps to the origin (boarding comes after)
    ],
)
def test_mb_vehicle_assigned_at_the_origin_counts_as_picked_up(start, picked, node_next):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 1, 5)], [start])
    eng = AuthorsEngine(sc, "mb", PRESET)
    veh = eng.vehicles[0]
    eng._apply(130.0, {0: (0,)}, [0])
    assert veh.passenger == 0 and veh.picked_up is picked
    assert veh.active_at == 0.0 and veh.node == net.index_of([start])[0]  # MB moves nobody it has just assigned
    eng._apply(140.0, {}, [0])  # 140 s > 120 s (first link) since it was last active
    assert veh.node == net.index_of([node_next])[0]


def test_idle_vehicle_jumps_in_the_batch_it_draws_then_walks_back_along_the_route():
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 5, 6)], [0])
    eng = AuthorsEngine(sc, "mb", PRESET)
    veh = eng.vehicles[0]
    node = {int(i): n for n, i in enumerate(net.index_of(list(range(7))))}
    eng._idle(veh, 130.0)  # draws node 5 and, 130 s > 120 s, jumps there at once
    assert node[veh.node] == 5 and veh.reposition_s == 130.0
    eng._idle(veh, 250.0)  # 120 s since the last move: not more than the first link
    assert node[veh.node] == 5
    seen = []
    for t in (251.0, 380.0, 510.0, 640.0):  # then one node back along the route per batch
        eng._idle(veh, t)
        seen.append(node[veh.node])
    assert seen == [4, 3, 2, 1]
    eng._idle(veh, 770.0)  # route used up: draws node 5 again, jumps (130 s > 120 s)
    assert node[veh.node] == 5
