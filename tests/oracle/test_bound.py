"""The proven upper bound (docs/bound.md): its graph holds every pair a run forms, its weights cover every
realised saving, it is solved exactly, and the checker certifies it (and catches an inflated pair)."""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest
from helpers import line_network, scenario_of

from rpbench import results
from rpbench.check import bound_weights, check_folder
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import run_comparison
from rpbench.oracle import find_candidates, solve_oracle
from rpbench.oracle.pairs import PairRules, bound_rules
from rpbench.scenarios import ScenarioRequest, build_scenario
from rpbench.spec import RunSpec

STRATEGIES = ["np", "mb", "rtv", "fl-nd", "fl", "hindsight"]


def _frame(scenario) -> pd.DataFrame:
    o = scenario.orders
    return pd.DataFrame(
        {"request_s": o.request_s, "patience_s": o.patience_s, "origin": o.origin, "destination": o.destination}
    )


@pytest.mark.parametrize(
    "seed, overrides",
    [(0, {}), (5, {}), (1, {"max_pickup_m": 700.0}), (2, {"max_pickup_m": 600.0, "patience_mean_s": 40.0})],
)
def test_enumeration_equals_a_brute_force_over_all_pairs(seed, overrides):
    """Every pair whose checker-computed bound weight is finite is a candidate, with that weight (a small R̄
    makes the vehicle turn further along the first passenger's path: the walk is exercised)."""
    sc = build_scenario("toy", sample=0.2, seed=seed, param_overrides=overrides)
    dist = sc.network.distances().dist
    cands = find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    n = len(sc.orders)
    a, b = np.triu_indices(n, k=1)
    solo = dist[sc.orders.origin, sc.orders.destination]
    weight, edge = bound_weights(sc.network.distances(), _frame(sc), solo, sc.params, a, b)
    expected = {(int(x), int(y)): w for x, y, w in zip(a[edge], b[edge], weight[edge], strict=True)}
    found = {(int(lo), int(hi)): w for lo, hi, w in zip(cands.low, cands.high, cands.saving_m, strict=True)}
    assert found.keys() == expected.keys() and len(found) > 20
    assert all(found[k] == pytest.approx(expected[k], abs=1e-9) for k in found)


def test_the_first_passenger_has_driven_on_when_a_late_second_is_revealed():
    """A is picked up by t_A + K_A + R̄/v = 450 s at the latest; B, 500 m behind A's origin, is revealed 120 s
    later, when A's vehicle has driven at least 1,000 m along A's path: it turns at node 2, not at o_A
    (saving 3,500 m, not the 4,500 m of turning at A's origin), in the enumeration and in the checker."""
    net = line_network(11, 500.0)
    sc = scenario_of(net, [(0.0, 0, 10), (570.0, 1, 10)], [6], patience_s=90.0)
    cands = find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    assert len(cands) == 1 and (cands.first[0], cands.second[0]) == (0, 1)
    assert cands.saving_m[0] == pytest.approx(3500.0) and cands.length_m[0] == pytest.approx(6000.0)
    solo = sc.network.distances().dist[sc.orders.origin, sc.orders.destination]
    weight, edge = bound_weights(sc.network.distances(), _frame(sc), solo, sc.params, np.array([0]), np.array([1]))
    assert edge[0] and weight[0] == pytest.approx(3500.0)
    # revealed earlier, while A may still wait for its pick-up, B can join at A's origin
    early = scenario_of(net, [(0.0, 0, 10), (400.0, 1, 10)], [6], patience_s=90.0)
    cands = find_candidates(early.network.distances(), early.orders, bound_rules(early.params))
    assert cands.saving_m[0] == pytest.approx(4500.0)


def test_the_bound_contains_the_paper_oracle_pairs():
    """Oracle-1's pairs (requests within K̄, h = o_A) are bound edges: the bound is at least Oracle-1."""
    sc = build_scenario("toy", sample=0.3, seed=1)
    one = solve_oracle(sc, 1, "matching")
    bound = solve_oracle(
        sc, 1, "matching", candidates=find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    )
    assert bound.is_upper_bound and not one.is_upper_bound
    assert bound.kpis()["total_saving_km"] >= one.kpis()["total_saving_km"] > 0


def test_every_exact_preset_proves_the_same_bound():
    sc = build_scenario("toy", sample=0.25, seed=2)
    cands = find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    values = {}
    for preset in ("matching", "highs", "scipy", "cvxpy-highs", "pyomo-highs", "blossom-v"):
        from rpbench.backends import load_preset

        if not load_preset(preset).is_installed():
            continue
        r = solve_oracle(sc, 1, preset, candidates=cands)
        assert r.status.value == "optimal", preset
        values[preset] = r.upper_bound_m
    assert len(values) >= 3 and len(set(values.values())) == 1


def test_rounding_up_keeps_it_a_bound():
    """The model's values are savings rounded up to the unit: its optimum is >= the unrounded one."""
    sc = build_scenario("toy", sample=0.2, seed=3)
    cands = find_candidates(sc.network.distances(), sc.orders, bound_rules(sc.params))
    r = solve_oracle(sc, 1, "matching", candidates=cands, unit_m=100.0)  # a coarse unit on purpose
    assert r.upper_bound_m >= r.total_saving_m
    exact = solve_oracle(sc, 1, "matching", candidates=cands)
    assert r.upper_bound_m >= exact.total_saving_m - 1e-6


def test_the_bound_rules_cannot_be_relaxed_or_tightened():
    with pytest.raises(ParameterError, match="cannot be changed"):
        PairRules(window="bound", pickup_check=True, both_pickup_orders=True)
    with pytest.raises(ParameterError, match="cannot be changed"):
        PairRules(window="bound")  # one pick-up order only
    with pytest.raises(ParameterError, match="window 'weekly'"):
        PairRules(window="weekly")


@pytest.mark.slow
@pytest.mark.parametrize(
    "seed, sample, overrides",
    [
        (0, 0.5, {}),
        (1, 0.4, {"dt_s": 30.0}),
        (2, 0.6, {"max_detour_m": 1500.0}),
        (3, 0.5, {"vehicles_per_100_orders": 10.0}),
        (4, 0.7, {"patience_mean_s": 300.0, "planner_patience_s": 300.0}),
    ],
)
def test_certificate_holds_for_every_strategy_on_random_toy_scenarios(tmp_path, seed, sample, overrides):
    request = ScenarioRequest("toy", sample=sample, seed=seed, params=tuple(overrides.items()))
    spec = RunSpec.of(request, [*STRATEGIES, "bound"], oracle_preset="matching")
    outcome = run_comparison(spec, tmp_path / "r", progress=False)
    folder, table = outcome.folder, outcome.table
    checks = {rc.run: rc for rc in check_folder(folder)}
    assert all(rc.ok for rc in checks.values()), {k: v.violations for k, v in checks.items() if not v.ok}
    assert sum(checks[s].checked["certified_pairs"] for s in STRATEGIES) > 0
    ratios = table.loc["competitive_ratio_bound", STRATEGIES]
    assert (ratios <= 1.0).all() and (ratios >= -1e-9).all()  # NP saves 0 up to float rounding


@pytest.fixture(scope="module")
def bounded_run(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.4, seed=7), ["mb", "bound"], oracle_preset="matching")
    folder = run_comparison(spec, tmp_path_factory.mktemp("b") / "run", progress=False).folder
    return folder


def _copy(folder, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    return copy


def _violations(folder) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for rc in check_folder(folder):
        for check, messages in rc.violations.items():
            out.setdefault(check, []).extend(messages)
    return out


def test_clean_run_is_certified(bounded_run):
    checks = {rc.run: rc for rc in check_folder(bounded_run)}
    assert checks["mb"].ok and checks["bound"].ok and checks["mb"].checked["certified_pairs"] > 0


def test_an_inflated_pair_saving_fails_the_certificate(bounded_run, tmp_path):
    """Shorten the odometer of a pair's last drop-off: its realised saving exceeds the edge weight."""
    run = _copy(bounded_run, tmp_path)
    events = pd.read_csv(run / "runs" / "mb" / "events.csv.gz")
    pair = events[(events["event"] == "assign") & (events["partner"] >= 0)].iloc[0]
    a, b = int(pair["order"]), int(pair["partner"])
    drops = events[(events["event"] == "dropoff") & events["order"].isin([a, b])]
    last = drops.sort_values("t_s").iloc[-1]
    path = run / "runs" / "mb" / "trajectories.npz"
    traj = results.load_trajectories(path)
    lo, hi = traj["vehicle_offsets"][int(last["vehicle"])], traj["vehicle_offsets"][int(last["vehicle"]) + 1]
    k = (
        lo
        + np.flatnonzero((np.abs(traj["t_s"][lo:hi] - last["t_s"]) < 1e-6) & (traj["node"][lo:hi] == last["node"]))[0]
    )
    traj["odo_m"][k:hi] -= 5000.0  # 5 km less occupied driving
    results.save_trajectories(path, traj)
    found = _violations(run)
    assert "bound-certificate" in found and "exceeds the bound's edge weight" in " ".join(found["bound-certificate"])


def test_a_lowered_bound_fails_by_name(bounded_run, tmp_path):
    run = _copy(bounded_run, tmp_path)
    kpis = pd.read_csv(run / "kpis.csv")
    sel = (kpis["run"] == "bound") & (kpis["kpi"] == "total_saving_km")
    kpis.loc[sel, "value"] = 0.001
    kpis.to_csv(run / "kpis.csv", index=False)
    found = _violations(run)
    assert "kpi" in found and "bound-certificate" in found  # the bound's KPI, and mb's saving above it


def test_a_pair_outside_the_window_is_not_an_edge(bounded_run, tmp_path):
    """Move a paired order's request an hour earlier: the pair can no longer be formed."""
    run = _copy(bounded_run, tmp_path)
    events = pd.read_csv(run / "runs" / "mb" / "events.csv.gz")
    pair = events[(events["event"] == "assign") & (events["partner"] >= 0)].iloc[0]
    orders = pd.read_csv(run / "orders.csv.gz")
    orders.loc[int(pair["partner"]), "request_s"] -= 3600.0
    orders.to_csv(run / "orders.csv.gz", index=False)
    found = _violations(run)
    assert any("not an edge" in m for m in found.get("bound-certificate", []))
