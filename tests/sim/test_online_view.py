"""What the simulator hands a strategy before the first round: an online one the view without orders, a
clairvoyant one the whole scenario, and the run says which."""

from __future__ import annotations

import pytest
from helpers import line_network, scenario_of

from rpbench.backends.presets import load_preset
from rpbench.exceptions import LookaheadError
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.sim.simulator import Simulator
from rpbench.strategies.myopic import MyopicBatch


class Spy(MyopicBatch):
    """MB, keeping what prepare received."""

    def prepare(self, scenario):
        self.given = scenario


class Peeker(Spy):
    """Online, yet counts the day's orders before the day."""

    name = "peek"

    def prepare(self, scenario):
        super().prepare(scenario)
        self.n_orders = len(scenario.orders)


class Seer(Peeker):
    """The same, declared clairvoyant."""

    name = "seer"
    clairvoyant = True


@pytest.fixture(scope="module")
def preset():
    return load_preset("highs")


@pytest.fixture
def scenario():
    return scenario_of(line_network(6), [(0.0, 0, 3), (10.0, 1, 5), (30.0, 4, 0)], vehicles=[0, 5])


def test_an_online_strategy_gets_the_view(scenario, preset):
    spy = Spy()
    sim = Simulator(scenario, spy, preset).run()
    assert isinstance(spy.given, OnlineView) and spy.given.network is scenario.network
    assert spy.given.reader == f"strategy 'mb' ({__name__}.Spy)"
    assert not sim.clairvoyant and len(sim.events)


def test_an_online_strategy_reading_the_orders_fails_naming_it(scenario, preset):
    with pytest.raises(LookaheadError) as info:
        Simulator(scenario, Peeker(), preset).run()
    assert str(info.value) == (
        f"strategy 'peek' ({__name__}.Peeker) read the scenario's orders before they were revealed: online "
        "strategies see orders only as they are revealed in RoundState; declare `clairvoyant = True` to read the "
        "future"
    )


def test_a_clairvoyant_strategy_reads_them_and_its_run_says_so(scenario, preset):
    seer = Seer()
    sim = Simulator(scenario, seer, preset).run()
    assert isinstance(seer.given, Scenario) and seer.n_orders == 3
    assert sim.clairvoyant
    # the same decisions as MB: reading the future changed nothing here but the record
    mb = Simulator(scenario, MyopicBatch(), preset).run()
    assert sim.events.equals(mb.events)
    assert Seer().describe()["clairvoyant"] and not MyopicBatch().describe()["clairvoyant"]
