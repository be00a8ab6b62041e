"""FL-perfect: FL's round with ē(p) and ē(0,p) from the realised orders; clairvoyant, checked like every run, its
values the savings of the realised partners, and FL itself when no partner exists."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from helpers import line_network, network_from_edges, round_state, scenario_of

from rpbench.backends import load_preset
from rpbench.check import check_folder
from rpbench.cli import main
from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.geometry import pool
from rpbench.harness.comparison import run_comparison
from rpbench.predict.savings import waiting_saving
from rpbench.results.metrics import kpis, occupied_distance_m, passenger_table
from rpbench.scenarios import ScenarioRequest, build_scenario
from rpbench.sim.simulator import Simulator
from rpbench.spec import RunSpec
from rpbench.strategies import Kind, make_strategy, strategy_class
from rpbench.strategies.forward import ForwardLooking
from rpbench.strategies.perfect import ForwardPerfect

#: Without the MB calibration run.
FIXED = {"tau0_s": 60.0, "mean_pickup_m": 900.0}


def test_it_is_registered_and_declared_clairvoyant():
    assert strategy_class("fl-perfect") is ForwardPerfect
    strategy = make_strategy("fl-perfect")
    assert strategy.clairvoyant is True and strategy.label == "FL-perfect"
    assert ForwardPerfect.calibrated_by == "mb" and ForwardPerfect.needs_calibration(strategy.options)
    assert not ForwardPerfect.needs_calibration(make_strategy("fl-perfect", **FIXED).options)
    with pytest.raises(LookaheadError, match="fl-perfect"):
        strategy.prepare(build_scenario("toy", sample=0.1, seed=0).online_view())


def test_a_future_perfect_partner_is_valued_at_its_saving():
    """p rides 0 -> 6; B, requested after the round, rides 1 -> 5 and can join p's vehicle at o_p before p is
    picked up: ē*(p) is POOL's saving of the pair, and waiting is worth FL's factor times the better of
    joining B's vehicle (ē*_s) and being joined later (ē*_later)."""
    net = line_network(7)
    scenario = scenario_of(net, [(1.0, 0, 6), (15.0, 1, 5)], [0])
    p = scenario.params
    strategy = make_strategy("fl-perfect", **FIXED)
    strategy.prepare(scenario)
    state = round_state(net, [(0, 6)], [(0, 300.0)], t=10.0)
    values = strategy.values(state)
    dist = net.distances().dist
    o, d = net.index_of([0, 1]), net.index_of([6, 5])
    taker = pool(dist, o[0], d[0], o[1], d[1], max_pickup_m=p.max_pickup_m, max_detour_m=p.max_detour_m)
    seeker = pool(dist, o[1], d[1], o[0], d[0], max_pickup_m=p.max_pickup_m, max_detour_m=p.max_detour_m)
    assert values.taker[0] == pytest.approx(float(taker.saving)) == pytest.approx(4000.0)
    assert values.later[0] == pytest.approx(4000.0)  # assigned later, still before B is revealed
    assert values.seeker[0] == pytest.approx(float(seeker.saving)) == pytest.approx(3000.0)  # B first, p joins at o_B
    wait = waiting_saving(np.array([4000.0]), 1, planner_patience_s=90.0, dt_s=10.0, response_rate=p.response_rate)
    assert values.wait[0] == pytest.approx(float(wait[0]))
    # FL's utilities on these values: ē²/(ē+pk)·α^k and ē(0,p) - l̄
    rm = strategy.build(state)
    vacant = int(np.flatnonzero(rm.kind == Kind.VACANT)[0])
    assert rm.utility_m[vacant] == pytest.approx(4000.0**2 / (4000.0 + 300.0) * p.alpha)
    assert rm.utility_m[rm.kind == Kind.WAIT][0] == pytest.approx(float(wait[0]) - 900.0)


def test_the_simulator_realises_the_value_when_the_pick_up_takes_tau0():
    """The vehicle is 500 m (60 s) from p: p takes it, B joins in its first round, and the run saves ē*(p)."""
    net = network_from_edges([(i, i + 1, 1000.0) for i in range(6)] + [(7, 0, 500.0)])
    scenario = scenario_of(net, [(0.0, 0, 6), (15.0, 1, 5)], [7])
    values: list[float] = []

    class Recorded(ForwardPerfect):
        def build(self, state):
            if state.t_s == 0.0:
                values.append(float(self.values(state).taker[0]))
            return super().build(state)

    res = Simulator(scenario, Recorded(tau0_s=60.0, mean_pickup_m=5000.0), load_preset("highs")).run()
    o = scenario.orders
    solo = net.distances().dist[o.origin, o.destination]
    tab = passenger_table(res.events, solo, o.request_s, res.trajectories)
    saving_km = kpis(tab, occupied_distance_m(res.events, res.trajectories), scenario.params)["total_saving_km"]
    assert tab["partner"].tolist() == [1, 0] and values == [pytest.approx(4000.0)]
    assert saving_km * 1000.0 == pytest.approx(values[0], abs=1e-6)


class NoFuture:
    """A prediction of no pairing at all: ē(p) = ē(0,p) = 0."""

    def lookup(self, o, d):
        return SimpleNamespace(e_vacant=np.zeros(len(o)))

    def e_wait(self, o, d, k_p, params):
        return np.zeros(len(o))


class FLNoFuture(ForwardLooking):
    def prepare(self, scenario):
        self.predictions = [NoFuture()]
        self.mean_pickup_m = np.array([self.options.mean_pickup_m])


def test_without_a_partner_it_is_fl_with_zero_savings():
    """Orders that never overlap in time: every ē* is 0, and the run is FL's with a prediction of 0."""
    net = line_network(7)
    orders = [(5.0 + 700.0 * i, i % 3, 6 - i % 2) for i in range(5)]
    scenario = scenario_of(net, orders, [3, 5])
    seen: list[np.ndarray] = []

    class Recorded(ForwardPerfect):
        def build(self, state):
            v = self.values(state)
            seen.append(np.concatenate([v.taker, v.seeker, v.later, v.wait]))
            return super().build(state)

    runs = [Simulator(scenario, s(**FIXED), load_preset("highs")).run() for s in (Recorded, FLNoFuture)]
    assert seen and not np.concatenate(seen).any()
    perfect, fl = (r.events.reset_index(drop=True) for r in runs)
    assert perfect.equals(fl)


def test_its_run_on_the_toy_city_passes_the_checker_calibrated_by_mb(tmp_path):
    spec = RunSpec.of(
        ScenarioRequest("toy", sample=0.2, seed=3), ["mb", "fl-perfect", "bound"], oracle_preset="matching"
    )
    outcome = run_comparison(spec, tmp_path / "run", progress=False)
    folder, table = outcome.folder, outcome.table
    checks = check_folder(folder)
    assert all(rc.ok for rc in checks), {rc.run: rc.violations for rc in checks if not rc.ok}
    meta = json.loads((folder / "meta.json").read_text())
    run = meta["runs"]["fl-perfect"]
    assert run["clairvoyant"] is True and meta["runs"]["mb"]["clairvoyant"] is False
    assert run["options"]["tau0_s"] == pytest.approx(table.loc["avg_pickup_time_s", "mb"])  # as FL's, A4
    assert run["options"]["mean_pickup_m"] == pytest.approx(table.loc["avg_pickup_distance_m", "mb"])
    assert 0 < table.loc["total_saving_km", "fl-perfect"] <= table.loc["total_saving_km", "bound"]


@pytest.mark.parametrize(
    "opt, message",
    [
        ("fl-perfect.tau0_s=-5", "option tau0_s = -5.0 is out of range (0 <= value <= 86400 s)"),
        ("fl-perfect.mean_pickup_m=far", "option mean_pickup_m"),
        (
            "fl-perfect.rates=month",
            "fl-perfect: unknown option 'rates'; known options: order_rule, tau0_s, mean_pickup_m",
        ),
        ("fl-perfect.order_rule=nearest", "option order_rule = 'nearest' must be one of"),
    ],
)
def test_a_bad_option_is_one_error_line(tmp_path, capsys, opt, message):
    out = tmp_path / "never"
    argv = ["run", "--scenario", "toy", "--sample", "0.1", "--strategies", "fl-perfect", "--opt", opt]
    assert main([*argv, "--no-progress", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not out.exists()
    with pytest.raises(ParameterError, match="tau0_s"):
        make_strategy("fl-perfect", tau0_s=1e9)
