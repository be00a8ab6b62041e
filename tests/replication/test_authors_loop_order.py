"""Details of the authors' loop that the published RTV code showed when run step by step beside the engine.

Running the authors' published RTV folder and this engine round by round on 2017-05-02
(docs/replication.md) found three places where the engine's state parted from theirs:
the order in which a round's new passengers are listed, the list idle vehicles draw
targets from, and a vehicle assigned while already standing at its passenger's origin.
Line networks have 1,000 m links (120 s each at the authors' 0.12 s/m).
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
    """Keeps the passenger list each RTV round was built from."""

    def _match_rtv(self, t, seekers, active):
        self.rounds = getattr(self, "rounds", []) + [(t, list(seekers))]
        return super()._match_rtv(t, seekers, active)


def test_a_rounds_new_passengers_follow_the_release_rank():
    net = line_network(8)
    sc = scenario_of(net, [(5.0, 1, 6), (6.0, 2, 4)], [0])
    by_time = _Recording(sc, "rtv", PRESET)
    by_time.run()
    by_rank = _Recording(sc, "rtv", PRESET, release_rank=np.array([1, 0]))
    by_rank.run()
    assert by_time.rounds[0] == (10.0, [0, 1])
    assert by_rank.rounds[0] == (10.0, [1, 0])          # the authors' sample order, not the request time


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
    assert veh.node == origins[0]                        # not the released orders' origin (node 5)


@pytest.mark.parametrize("start, picked, active_at, node", [
    (1, True, 0.0, 1),          # at the origin: picked up at once, activity time kept
    (0, False, 130.0, 1),       # one link away, 130 s > 120 s since it was last active: jumps, reset to now
])
def test_rtv_vehicle_assigned_at_the_origin_counts_as_picked_up(start, picked, active_at, node):
    net = line_network(7)
    sc = scenario_of(net, [(5.0, 1, 5)], [start])
    eng = AuthorsEngine(sc, "rtv", PRESET)
    veh = eng.vehicles[0]
    eng._apply(130.0, {0: (0,)}, [0])
    assert veh.p0 == 0 and veh.picked is picked
    assert veh.active_at == active_at
    assert veh.node == net.index_of([node])[0]


def test_the_paper_input_carries_sample_order_and_idle_origins(data_dir):
    paper = load_paper_input(data_dir, date="2017-05-02")
    orders = paper.scenario.orders
    assert len(paper.idle_origins) == 477                # distinct origins of all 928 sampled orders
    # The fleet is placed on the same list (random.seed(i); random.choice(origins)).
    placed = [random.Random(i).choice(list(paper.idle_origins)) for i in range(len(paper.scenario.fleet))]
    assert np.array_equal(paper.scenario.fleet.initial_node, placed)
    rank = paper.sample_rank
    assert len(rank) == len(orders) and len(np.unique(rank)) == len(rank) and rank.max() < 928
    assert not np.all(np.diff(rank) > 0)                 # sample order is not request-time order


def test_run_authors_passes_the_inputs_order_and_origins(monkeypatch):
    from rpbench.replication import runner
    from rpbench.replication.runner import Inputs, run_authors
    from rpbench.replication.switches import Switches
    from rpbench.scenarios.paper_input import PaperInput

    seen = {}

    class Capture(AuthorsEngine):
        def __init__(self, *args, **kwargs):
            seen.update(kwargs)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(runner, "AuthorsEngine", Capture)
    net = line_network(4)
    paper = PaperInput(scenario_of(net, [(5.0, 0, 3)], [1]), predictions=None, response_denominator=7,
                       sample_rank=np.array([4]), idle_origins=net.index_of([2]))
    run_authors(Inputs(paper=paper, peak=paper), "rtv", Switches(), PRESET)
    assert list(seen["release_rank"]) == [4] and list(seen["reposition_origins"]) == list(net.index_of([2]))
