"""A run's transitions and rewards: a hand-made run checked row by row, and a toy MB run whose rewards
add up to its KPI saving (``pair_savings`` read off the same passenger table as ``total_saving_km``).

The hand-made run: three cells (node i is cell i), two bins of 100 s, γ = 0.5 per bin.  Vacant rounds::

    vehicle 0:  t = 0 at node 0,  t = 50 at node 1,  t = 150 at node 2
    vehicle 1:  t = 20 at node 2, t = 120 at node 0

Pairs delivered: vehicle 0 at 50 s (saving 1000 m: at the instant of its next observation, so it belongs
to the one at 0 s) and at 200 s (500 m, after its last observation: the terminal transition's reward),
vehicle 1 at 110 s (300 m, belongs to its observation at 20 s).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rpbench.backends import load_preset
from rpbench.harness.training import recording
from rpbench.results import metrics
from rpbench.scenarios.registry import build_scenario
from rpbench.sim.simulator import Simulator
from rpbench.strategies.myopic import MyopicBatch
from rpbench.valuefn.cells import Grid
from rpbench.valuefn.transitions import Observations, Transitions, transitions_of_run

GRID = Grid(cell_m=1000.0, bin_s=100.0, n_bins=2, node_cell=np.array([0, 1, 2]), n_cells=3)
#: Rounds (t, V0 vehicles, their nodes), as the simulator's rounds list them.
ROUNDS = [
    (0.0, np.array([0]), np.array([0])),
    (20.0, np.array([1]), np.array([2])),
    (50.0, np.array([0]), np.array([1])),
    (120.0, np.array([1]), np.array([0])),
    (150.0, np.array([0]), np.array([2])),
]


def pairs(rows: list[tuple[int, float, float]]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["vehicle", "done_s", "saving_m"])


def test_observations_of_rounds_concatenate_in_round_order():
    obs = Observations.of_rounds([(10.0, np.array([3, 1]), np.array([7, 8])), (20.0, np.array([2]), np.array([9]))])
    assert obs.t_s.tolist() == [10.0, 10.0, 20.0]
    assert obs.vehicle.tolist() == [3, 1, 2] and obs.node.tolist() == [7, 8, 9]
    empty = Observations.of_rounds([])
    assert len(empty.t_s) == len(empty.vehicle) == len(empty.node) == 0


def test_the_hand_made_run_row_by_row():
    """Rows in (vehicle, time) order; each pair's saving discounted from its delivery to the row's start;
    γ of the next state = 0.5^(Δt / 100 s); a vehicle's last observation leads to the terminal state."""
    tr = transitions_of_run(
        Observations.of_rounds(ROUNDS), pairs([(0, 50.0, 1000.0), (1, 110.0, 300.0), (0, 200.0, 500.0)]), GRID, 0.5
    )
    assert len(tr) == 5
    assert tr.t_s.tolist() == [0.0, 50.0, 150.0, 20.0, 120.0]
    # state = cell * 2 + bin: (node 0, 0 s) 0, (node 1, 50 s) 2, (node 2, 150 s) 5, (node 2, 20 s) 4, (node 0, 120 s) 1
    assert tr.state.tolist() == [0, 2, 5, 4, 1]
    assert tr.next_state.tolist() == [2, 5, -1, 1, -1]
    assert tr.gamma == pytest.approx([0.5**0.5, 0.5**1.0, 0.0, 0.5**1.0, 0.0], rel=1e-15)
    assert tr.reward_m == pytest.approx([1000.0 * 0.5**0.5, 0.0, 500.0 * 0.5**0.5, 300.0 * 0.5**0.9, 0.0], rel=1e-15)


def test_pairs_delivered_together_add_up_and_no_pair_gives_no_reward():
    obs = Observations.of_rounds(ROUNDS)
    tr = transitions_of_run(obs, pairs([(1, 110.0, 300.0), (1, 60.0, 100.0)]), GRID, 0.5)
    assert tr.reward_m[3] == pytest.approx(300.0 * 0.5**0.9 + 100.0 * 0.5**0.4, rel=1e-15)
    assert tr.reward_m[[0, 1, 2, 4]].tolist() == [0.0] * 4
    none = transitions_of_run(obs, pairs([]), GRID, 0.5)
    assert none.reward_m.tolist() == [0.0] * 5 and none.next_state.tolist() == tr.next_state.tolist()
    # γ = 1: rewards are the savings themselves
    assert transitions_of_run(obs, pairs([(0, 50.0, 1000.0)]), GRID, 1.0).reward_m[0] == 1000.0


@pytest.mark.parametrize(
    "pair, message",
    [
        ((1, 10.0, 300.0), "vehicle 1 delivered a pair at 10 s before any vacant round"),  # its first is at 20 s
        ((1, 20.0, 300.0), "vehicle 1 delivered a pair at 20 s before any vacant round"),  # strictly before
        ((0, 0.0, 300.0), "vehicle 0 delivered a pair at 0 s before any vacant round"),
        ((2, 500.0, 300.0), "vehicle 2 delivered a pair at 500 s before any vacant round"),  # never vacant
    ],
)
def test_a_pair_before_its_vehicles_first_observation_is_an_error(pair, message):
    with pytest.raises(ValueError, match=message):
        transitions_of_run(Observations.of_rounds(ROUNDS), pairs([(0, 50.0, 1000.0), pair]), GRID, 0.5)


def test_no_observation_gives_no_transition():
    tr = transitions_of_run(Observations.of_rounds([]), pairs([]), GRID, 0.9)
    assert len(tr) == 0 and tr.state.dtype == np.int64


def test_concat_keeps_every_row_in_order():
    one = transitions_of_run(Observations.of_rounds(ROUNDS[:2]), pairs([]), GRID, 0.5)
    two = transitions_of_run(Observations.of_rounds(ROUNDS[2:]), pairs([]), GRID, 0.5)
    both = Transitions.concat([one, two])
    assert len(both) == len(one) + len(two) == 5
    assert both.t_s.tolist() == [*one.t_s, *two.t_s]
    assert both.state.tolist() == [*one.state, *two.state]


@pytest.fixture(scope="module")
def toy_mb():
    """A toy MB run (40% of the orders) with every round's vacant vehicles recorded."""
    scenario = build_scenario("toy", sample=0.4, seed=5)
    log: list = []
    sim = Simulator(scenario, recording(MyopicBatch(), log), load_preset("highs")).run()
    o = scenario.orders
    solo = scenario.network.distances()(o.origin, o.destination)
    tab = metrics.passenger_table(sim.events, solo, o.request_s, sim.trajectories)
    kpis = metrics.kpis(tab, metrics.occupied_distance_m(sim.events, sim.trajectories), scenario.params)
    return scenario, tab, kpis, log


def test_pair_savings_agree_with_the_kpi_saving(toy_mb):
    """One row per served pair, on the pair's vehicle, done at its last drop-off; the savings add up to
    total_saving_km."""
    _, tab, kpis, _ = toy_mb
    ps = metrics.pair_savings(tab)
    assert kpis["pairs"] >= 10 and len(ps) == kpis["pairs"]
    assert ps["saving_m"].sum() / 1000 == pytest.approx(kpis["total_saving_km"], rel=1e-9)
    lead = np.flatnonzero(tab["pooled"].to_numpy() & (tab["partner"].to_numpy() > np.arange(len(tab))))
    partner = tab["partner"].to_numpy()[lead]
    assert ps["vehicle"].tolist() == tab["vehicle"].to_numpy()[lead].tolist()
    assert (tab["vehicle"].to_numpy()[partner] == ps["vehicle"].to_numpy()).all()
    drop = tab["dropoff_s"].to_numpy()
    assert ps["done_s"].tolist() == np.maximum(drop[lead], drop[partner]).tolist()
    # a pair's saving is l_A + l_B - L, L the vehicle's odometer from the first pick-up to the last drop-off
    solo = tab["solo_m"].to_numpy()
    assert (ps["saving_m"].to_numpy() <= solo[lead] + solo[partner] + 1e-6).all()


def test_pair_savings_of_a_run_without_pairs_is_empty(toy_mb):
    _, tab, _, _ = toy_mb
    none = tab.assign(partner=-1, pooled=False)
    assert len(metrics.pair_savings(none)) == 0
    assert list(metrics.pair_savings(none).columns) == ["vehicle", "done_s", "saving_m"]


def test_a_toy_runs_rewards_add_up_to_its_saving(toy_mb):
    """With γ = 1 nothing is discounted: the run's rewards sum to total_saving_km; every vehicle ever vacant
    ends in exactly one terminal transition."""
    scenario, tab, kpis, log = toy_mb
    obs = Observations.of_rounds(log)
    grid = Grid.of(scenario.network, 1000.0, 600.0, scenario.horizon_s)
    tr = transitions_of_run(obs, metrics.pair_savings(tab), grid, 1.0)
    assert len(tr) == len(obs.t_s) > 0
    assert tr.reward_m.sum() / 1000 == pytest.approx(kpis["total_saving_km"], rel=1e-9)
    assert (tr.next_state == -1).sum() == len(np.unique(obs.vehicle))
    assert ((tr.gamma == 1.0) == (tr.next_state >= 0)).all()
    discounted = transitions_of_run(obs, metrics.pair_savings(tab), grid, 0.9)
    assert 0 < discounted.reward_m.sum() < tr.reward_m.sum()
    assert (((discounted.gamma < 1.0) & (discounted.gamma > 0.0)) == (discounted.next_state >= 0)).all()
