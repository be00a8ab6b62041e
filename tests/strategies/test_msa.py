"""MSA (docs/sampling.md): online, reproducible, checked, and right on hand-made rounds."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from helpers import line_network, round_state, scenario_of

from rpbench.backends import load_preset
from rpbench.cli import main
from rpbench.commands._runs import parse_runs
from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.scenarios import ScenarioRequest
from rpbench.scenarios.base import Demand, History
from rpbench.strategies import Kind, make_strategy
from rpbench.strategies.msa import Futures

OPTIONS = {"order_rule", "samples", "horizon_s", "rule", "seed", "volume"}


@pytest.fixture(scope="module")
def toy():
    return ScenarioRequest("toy", sample=0.25, seed=3).build()


# ----------------------------------------------------------------------------------- online
def test_prepare_reads_the_online_view_only(toy):
    view = toy.online_view("strategy 'msa' (rpbench.strategies.msa.MultipleScenario)")
    with pytest.raises(LookaheadError, match="strategy 'msa' .* read the scenario's orders before they were revealed"):
        _ = view.orders
    s = make_strategy("msa")
    s.prepare(view)  # a read of the orders would raise here
    assert not s.clairvoyant and not s.clairvoyant_on(toy)
    assert s.rates and s.rates[0].total_per_s > 0  # the toy city's past days, not its realised orders


def test_a_scenario_without_demand_history_is_one_line():
    net = line_network(4)
    scenario = scenario_of(net, [(0.0, 0, 3)], [0])  # Demand(): only its own orders, which msa may not read
    with pytest.raises(ParameterError, match="msa' samples its futures from the demand known before the day") as err:
        make_strategy("msa").prepare(scenario.online_view())
    assert "\n" not in str(err.value)


def test_two_runs_give_the_same_events_and_another_seed_other_futures(toy):
    from rpbench.harness.comparison import simulate_strategy

    preset = load_preset("highs")
    first, second = (simulate_strategy(toy, "msa", preset, progress=False) for _ in range(2))
    assert len(first.sim.events) > 0
    assert first.sim.events.equals(second.sim.events)
    # the futures come from one stream seeded by the option and the scenario's seed
    draws = {}
    for seed in (0, 0, 1):
        s = make_strategy("msa", seed=seed)
        s.prepare(toy.online_view())
        draws.setdefault(seed, []).append(s.sample(600.0))
    same, other = draws[0], draws[1][0]
    assert np.array_equal(same[0].arrival_s, same[1].arrival_s) and np.array_equal(same[0].origin, same[1].origin)
    assert not (len(other) == len(same[0]) and np.array_equal(other.arrival_s, same[0].arrival_s))


def test_a_run_passes_the_checker(tmp_path):
    from rpbench.check import check_folder
    from rpbench.harness.comparison import run_comparison
    from rpbench.spec import RunSpec

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=8), ["mb", "msa"])
    outcome = run_comparison(spec, tmp_path / "msa", progress=False)
    results = {rc.run: rc for rc in check_folder(outcome.folder)}
    assert set(results) == {"mb", "msa"}
    assert all(rc.ok for rc in results.values()), {name: rc.violations for name, rc in results.items()}
    ran = results["msa"].checked  # the checks ran on its events, its KPIs and its pairs
    assert ran.get("events", 0) > 0 and ran.get("kpis", 0) > 0 and ran.get("certified_pairs", 0) > 0
    meta = json.loads((outcome.folder / "meta.json").read_text())
    assert meta["runs"]["msa"]["clairvoyant"] is False
    assert meta["runs"]["msa"]["options"]["samples"] == 8


# ----------------------------------------------------------------------------------- options
def test_rpbench_list_names_it_with_its_options(capsys):
    assert main(["list", "--json"]) == 0
    listed = {s["name"]: s for s in json.loads(capsys.readouterr().out)["strategies"]}
    assert listed["msa"]["label"] == "MSA"
    assert set(listed["msa"]["options"]) == OPTIONS
    assert "(default 8)" in listed["msa"]["options"]["samples"]


@pytest.mark.parametrize(
    "item, message",
    [
        ("msa.samples=0", "msa: option samples = 0 is out of range (an integer 1 <= value <= 256)"),
        ("msa.samples=2.5", "msa: option samples = '2.5' must be an integer"),
        ("msa.horizon_s=-5", "msa: option horizon_s = -5.0 is out of range (0 <= value <= 3600 s)"),
        ("msa.rule=majority", "msa: option rule = 'majority' must be one of consensus, regret"),
        ("msa.volume=big", "msa: option volume = 'big' must be one of table, observed"),
        ("msa.seed=-1", "msa: option seed = -1 is out of range"),
        ("msa.sample=3", "msa: unknown option 'sample'; known options: order_rule, samples, horizon_s"),
    ],
)
def test_bad_options_are_one_line(item, message):
    with pytest.raises(ParameterError) as err:
        parse_runs(["msa"], [item])
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_bad_option_on_the_command_line_is_one_error_line(capsys, tmp_path):
    code = main(
        ["run", "--scenario", "toy", "--strategies", "msa", "--opt", "msa.rule=vote", "--out", str(tmp_path / "x")]
    )
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("rpbench: error:")]
    assert code == 2 and len(lines) == 1 and "option rule = 'vote' must be one of consensus, regret" in lines[0]
    assert not (tmp_path / "x").exists()


# ----------------------------------------------------------------------------------- hand-made rounds
# A line 0-1-2-3-4-5 of 1 km links; R̄ = D̄ = 3 km, Δt = 10 s, K̄ = 90 s.  A waiting passenger p rides 2 -> 5.
# j, 0 -> 5, passes p's origin on its way: p joining j's vehicle saves 3 km (l_j + l_p - L = 5 + 3 - 5);
# the other way round (j joining p's vehicle) breaks p's detour (back to 0 and on to 5: 4 km > D̄).
NET = line_network(6)
P = (2, 5)
J = (0, 5)


def prepared(**options):
    """MSA prepared on the line (its demand history is never sampled: each test gives the futures)."""
    history = History(np.zeros(1), np.zeros(1, np.int32), np.full(1, 5, np.int32), days=1, source="tests")
    scenario = dataclasses.replace(scenario_of(NET, [(0.0, *P)], [2]), demand=Demand(table="history", history=history))
    s = make_strategy("msa", **options)
    s.prepare(scenario.online_view())
    return s


def futures_with_partner(t: float, present: list[bool], od=J, after_s: float = 20.0) -> Futures:
    """One order of OD ``od`` arriving ``after_s`` after ``t`` in the futures where ``present``."""
    where = np.flatnonzero(present).astype(np.int64)
    origin, destination = NET.index_of([od[0]])[0], NET.index_of([od[1]])[0]
    return Futures(
        where,
        np.full(len(where), origin, np.int64),
        np.full(len(where), destination, np.int64),
        np.full(len(where), t + after_s),
    )


def decide(s, state, futures):
    s.sample = lambda t_s: futures  # the futures of the current round, fixed
    return s.build(state), s.votes


def vacant_columns(rm, order):
    return int(((rm.kind == Kind.VACANT) & (rm.first == order)).sum())


def test_a_passenger_whose_partner_is_certain_to_come_waits():
    s = prepared()
    state = round_state(NET, [P], [(2, 0.0)])
    rm, votes = decide(s, state, futures_with_partner(0.0, [True] * 8))
    assert votes.wait_votes.tolist() == [8] and votes.wait.tolist() == [True]
    assert vacant_columns(rm, 0) == 0  # held back for the partner's vehicle
    assert rm.kind.tolist() == [Kind.WAIT] and rm.utility_m.tolist() == [-1e6]


def test_a_passenger_without_a_future_partner_is_assigned_now():
    s = prepared()
    state = round_state(NET, [P], [(2, 0.0)])
    # the futures hold an order going the other way (5 -> 0): no pair with p saves anything within D̄
    rm, votes = decide(s, state, futures_with_partner(0.0, [True] * 8, od=(5, 0)))
    assert votes.wait_votes.tolist() == [0] and votes.wait.tolist() == [False]
    assert vacant_columns(rm, 0) == 1
    assert rm.utility_m[(rm.kind == Kind.VACANT)].tolist() == [0.0]  # MB's -pk


def test_consensus_follows_the_majority_and_regret_the_saving_at_stake():
    state = round_state(NET, [P], [(2, 0.0)])
    few, most = [True] * 3 + [False] * 5, [True] * 5 + [False] * 3
    for present, waits in ((few, False), (most, True)):
        _, votes = decide(prepared(), state, futures_with_partner(0.0, present))
        assert votes.wait_votes.tolist() == [sum(present)] and votes.wait.tolist() == [waits]
    # regret (MSA-2): deciding now loses the 3 km pair in each future that holds the partner, waiting nothing
    _, votes = decide(prepared(rule="regret"), state, futures_with_partner(0.0, few))
    assert votes.loss_now[0] == pytest.approx(3000.0 * 3 / 8) and votes.loss_wait[0] == 0.0
    assert votes.wait.tolist() == [True]


def test_a_passenger_in_its_last_round_never_waits():
    s = prepared()
    # requested 85 s before a round at t = 90: the next round (100 s) is past K̄ = 90 s
    state = dataclasses.replace(round_state(NET, [P], [(2, 0.0)], t=90.0), p_request_s=np.array([5.0]))
    rm, votes = decide(s, state, futures_with_partner(90.0, [True] * 8))
    assert votes.last_round.tolist() == [True] and votes.wait.tolist() == [False]
    assert vacant_columns(rm, 0) == 1


def test_of_a_waiting_pair_the_first_is_dispatched_and_the_second_held_for_its_vehicle():
    # j (0 -> 5) and p (2 -> 5) both wait: j's vehicle can take p on its way, so j goes now and p waits
    s = prepared(horizon_s=0.0)
    state = round_state(NET, [J, P], [(0, 0.0), (2, 0.0)])
    rm, votes = decide(s, state, futures_with_partner(0.0, [False] * 8))
    assert votes.wait.tolist() == [False, True]
    assert vacant_columns(rm, 0) == 2 and vacant_columns(rm, 1) == 0


def test_a_waiting_passenger_keeps_only_joins_that_save_distance():
    # p waits for j; a partly occupied vehicle whose rider (3 -> 4) p could join only at a loss stays closed to p
    s = prepared()
    rider = {"node": 3, "origin": 3, "destination": 4, "delta": 0.0, "onboard": False}
    state = round_state(NET, [P], [], occupied=[rider])
    mb = make_strategy("mb").build(state)
    assert (mb.kind == Kind.JOIN).any()  # MB offers the join
    rm, votes = decide(s, state, futures_with_partner(0.0, [True] * 8))
    assert votes.wait.tolist() == [True] and not (rm.kind == Kind.JOIN).any()
