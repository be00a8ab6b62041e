"""Hindsight, the clairvoyant schedule: declared clairvoyant, checked like every run, at least MB's saving,
its plan on the upper bound's graph and its forecasts the savings the simulator realises."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rpbench.backends import load_preset
from rpbench.check import check_folder
from rpbench.cli import main
from rpbench.exceptions import LookaheadError
from rpbench.harness.comparison import run_comparison
from rpbench.oracle.pairs import bound_rules, find_candidates
from rpbench.results.metrics import kpis, occupied_distance_m, odometer_at, passenger_table
from rpbench.scenarios import ScenarioRequest, build_scenario
from rpbench.sim.simulator import Simulator
from rpbench.spec import RunSpec
from rpbench.strategies import make_strategy, strategy_class
from rpbench.strategies.hindsight import Hindsight


def simulate(scenario, name: str, **options):
    """The strategy after its run, the run's passenger table and its KPIs."""
    strategy = make_strategy(name, **options)
    res = Simulator(scenario, strategy, load_preset("highs")).run()
    o = scenario.orders
    solo = scenario.network.distances().dist[o.origin, o.destination]
    tab = passenger_table(res.events, solo, o.request_s, res.trajectories)
    return strategy, res, tab, kpis(tab, occupied_distance_m(res.events, res.trajectories), scenario.params)


def test_hindsight_is_registered_and_declared_clairvoyant():
    assert strategy_class("hindsight") is Hindsight
    assert Hindsight.clairvoyant is True
    assert make_strategy("hindsight").clairvoyant is True
    assert make_strategy("mb").clairvoyant is False


def test_an_online_view_is_refused():
    scenario = build_scenario("toy", sample=0.1, seed=0)
    with pytest.raises(LookaheadError, match="hindsight"):
        make_strategy("hindsight").prepare(scenario.online_view())


def test_its_run_on_the_toy_city_passes_the_checker_between_mb_and_the_bound(tmp_path):
    request = ScenarioRequest("toy", sample=0.3, seed=2)
    spec = RunSpec.of(request, ["mb", "hindsight", "bound"], oracle_preset="matching")
    outcome = run_comparison(spec, tmp_path / "run", progress=False)
    folder, table = outcome.folder, outcome.table
    checks = {rc.run: rc for rc in check_folder(folder)}
    assert all(rc.ok for rc in checks.values()), {k: v.violations for k, v in checks.items() if not v.ok}
    assert checks["hindsight"].checked["certified_pairs"] > 0
    saving = table.loc["total_saving_km"]
    assert saving["mb"] < saving["hindsight"] <= saving["bound"]
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["runs"]["hindsight"]["clairvoyant"] is True and meta["runs"]["mb"]["clairvoyant"] is False
    assert main(["check", str(folder)]) == 0


def test_a_hindsight_run_that_breaks_a_simulator_rule_fails_the_checker_by_name(tmp_path):
    """Its schedule is a lower bound on OPT only because it is checked: a join edited to a round after its
    passenger's patience ran out fails ``within-patience``, like any run's."""
    import pandas as pd

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=4), ["hindsight", "bound"], oracle_preset="matching")
    folder = run_comparison(spec, tmp_path / "run", progress=False).folder
    path = folder / "runs" / "hindsight" / "events.csv.gz"
    events = pd.read_csv(path)
    joins = events.index[(events["event"] == "assign") & (events["kind"] == "join")]
    events.loc[joins[0], "t_s"] += 3600.0
    events.to_csv(path, index=False)
    failed = {check for rc in check_folder(folder) for check in rc.violations}
    assert "within-patience" in failed


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_it_saves_at_least_what_mb_saves_on_small_toy_scenarios(seed):
    scenario = build_scenario("toy", sample=0.1, seed=seed)
    *_, hindsight = simulate(scenario, "hindsight")
    *_, mb = simulate(scenario, "mb")
    assert hindsight["total_saving_km"] >= mb["total_saving_km"] > 0


def test_every_planned_pair_is_an_edge_of_the_bound_graph():
    scenario = build_scenario("toy", sample=0.2, seed=4)
    strategy, _, tab, _ = simulate(scenario, "hindsight")
    cand = find_candidates(scenario.network.distances(), scenario.orders, bound_rules(scenario.params))
    edges = set(zip(cand.low.tolist(), cand.high.tolist(), strict=True))
    assert strategy.planned_pairs and strategy.planned_pairs <= edges
    partner = tab["partner"].to_numpy()
    realised = {(min(a, int(b)), max(a, int(b))) for a, b in enumerate(partner) if b >= 0}
    assert realised and realised <= edges


@pytest.mark.parametrize("seed", [0, 5])
def test_a_kept_plan_realises_exactly_its_forecast_saving(seed):
    """Every planned first records its partner and forecast saving when it takes a vacant vehicle; where that
    partner joined, the saving read off the odometers (l_A + l_B - L) is the forecast, to the millimetre."""
    scenario = build_scenario("toy", sample=0.2, seed=seed)
    strategy, res, tab, _ = simulate(scenario, "hindsight")
    solo, partner = tab["solo_m"].to_numpy(), tab["partner"].to_numpy()
    vehicle, pick, drop = tab["vehicle"].to_numpy(), tab["pickup_s"].to_numpy(), tab["dropoff_s"].to_numpy()
    kept = [(a, b, f) for a, (b, f) in strategy.commitments.items() if partner[a] == b]
    assert len(kept) >= 0.8 * len(strategy.commitments) > 0
    a, b, forecast = (np.array(x) for x in zip(*kept, strict=True))
    end = odometer_at(res.trajectories, vehicle[a], np.maximum(drop[a], drop[b]))
    realised = solo[a] + solo[b] - (end - odometer_at(res.trajectories, vehicle[a], pick[a]))
    np.testing.assert_allclose(realised, forecast, atol=1e-3)


def test_an_unknown_option_value_is_one_error_line(tmp_path, capsys):
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--sample",
            "0.1",
            "--strategies",
            "hindsight",
            "--opt",
            "hindsight.unplanned=sometimes",
            "--no-progress",
            "--out",
            str(tmp_path / "never"),
        ]
    )
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unplanned" in err[0] and not (tmp_path / "never").exists()


def test_the_kept_forecasts_of_firsts_not_yet_requested_are_those_the_round_would_compute(monkeypatch):
    """The plan keeps each edge's later-assignment forecast from the first plan that sees it; for every first
    not yet requested it must equal what :meth:`Hindsight._pair_values` computes in the current round."""
    compared = []
    kept_values = Hindsight._edge_values

    def both(self, state, vac, a, b, edge, lo_first, waiting, v1, upto):
        w, later = kept_values(self, state, vac, a, b, edge, lo_first, waiting, v1, upto)
        w_now, later_now = self._pair_values(state, vac, a, b, waiting, v1)
        np.testing.assert_array_equal(w, w_now)
        np.testing.assert_array_equal(later, later_now)
        compared.append(int((~waiting[a] & ~v1[a]).sum()))
        return w, later

    monkeypatch.setattr(Hindsight, "_edge_values", both)
    simulate(build_scenario("toy", sample=0.2, seed=4), "hindsight")
    assert len(compared) > 5 and sum(compared) > 100


def test_a_plan_is_made_again_early_only_when_one_of_its_pairs_breaks(monkeypatch):
    """With ``replan_s`` longer than the day, every plan after the first is a repair: made ``repair_s`` or
    more after the last, in a round where one of the last plan's pairs can no longer form; with ``repair_s``
    as long, there is one plan."""
    scenario = build_scenario("toy", sample=0.2, seed=0)
    day = scenario.horizon_s + 3600.0
    ages: list[float] = []
    due = Hindsight._plan_due

    def record(self, state):
        answer = due(self, state)
        if answer:
            ages.append(state.t_s - self._kept[0])
        return answer

    monkeypatch.setattr(Hindsight, "_plan_due", record)
    simulate(scenario, "hindsight", replan_s=day, repair_s=60.0)
    assert ages and all(60.0 - 1e-6 <= age < day for age in ages)
    ages.clear()
    simulate(scenario, "hindsight", replan_s=day, repair_s=day)
    assert ages == []
