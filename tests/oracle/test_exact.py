"""The exact offline optimum of lattice cities (docs/bound.md, "Exact optima on lattice cities"): two exact
solvers agree on it, the simulator realises it pair by pair and the checker verifies that, and on random small
cities every strategy's saving <= OPT <= U, hindsight included."""

from __future__ import annotations

import hashlib
import itertools
import json
import shutil

import numpy as np
import pandas as pd
import pytest
from check.tamper import run_violations

from rpbench.check import check_folder
from rpbench.cli import main
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import run_comparison
from rpbench.oracle.exact import PAIR, build_exact_model, extract_plan, lattice_view, order_rounds, solve_exact_model
from rpbench.scenarios import ScenarioRequest, build_scenario
from rpbench.spec import RunSpec

ONLINE = ["np", "mb", "rtv", "fl-nd", "fl"]


def _lattice(seed: int, sample: float = 0.15, **params):
    return build_scenario("lattice", sample=sample, seed=seed, param_overrides={"dt_s": 30.0, **params})


def test_rounds_follow_the_simulators_reveal_and_cancel_rules():
    """Revealed in the first round k with k·Δt >= t_req, cancelled once k·Δt - t_req > K (1e-9 tolerance)."""
    first, last = order_rounds(np.array([0.0, 10.0, 10.5, 29.999]), np.array([20.0, 20.0, 19.5, 0.0]), 10.0)
    assert first.tolist() == [0, 1, 2, 3] and last.tolist() == [2, 3, 3, 2]


def test_a_city_that_is_not_a_lattice_is_refused_in_one_line(capsys):
    with pytest.raises(ParameterError, match="needs a lattice city"):
        lattice_view(build_scenario("toy", sample=0.1, seed=0))
    code = main(["run", "--scenario", "toy", "--sample", "0.1", "--strategies", "exact", "--no-progress"])
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert code == 2 and len(errors) == 1 and "needs a lattice city" in errors[0]


def test_a_solve_stopped_before_any_plan_is_one_error_line_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(
        ["run", "--scenario", "lattice", "--sample", "0.8", "--strategies", "exact", "--opt", "exact.time_limit_s=1",
         "--out", str(out), "--no-progress"]
    )  # fmt: skip
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert code == 2 and len(errors) == 1 and "exact.time_limit_s" in errors[0] and not out.exists()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_exact_solvers_prove_the_same_optimum(seed):
    sc = _lattice(seed, sample=0.12)
    view = lattice_view(sc)
    model = build_exact_model(view, sc)
    highs = solve_exact_model(model, solver="highs")
    cpsat = solve_exact_model(model, solver="cp-sat")
    assert highs.proven and cpsat.proven and highs.objective == cpsat.objective > 0


def test_the_plan_decomposes_into_one_walk_per_vehicle_and_its_pairs_sum_to_the_optimum():
    sc = _lattice(3, sample=0.2)
    view = lattice_view(sc)
    model = build_exact_model(view, sc)
    sol = solve_exact_model(model)
    plan = extract_plan(model, sol)
    assert len(plan.vehicles) == len(sc.fleet)
    assert (
        sum(j["saving_blocks"] for vp in plan.vehicles for j in vp.jobs)
        == sol.objective
        == int(model.saving[sol.x > 0.5].sum())
    )
    taken = [j[k] for vp in plan.vehicles for j in vp.jobs for k in ("order_a", "order_b")]
    assert len(taken) == len(set(taken))  # each order in one pair at most
    for vp in plan.vehicles:  # a free vehicle moves one block per round
        rounds = sorted(vp.walk)
        for k0, k1 in itertools.pairwise(rounds):
            if k1 == k0 + 1:
                assert view.steps[vp.walk[k0], vp.walk[k1]] == 1
    assert (model.kind == PAIR).sum() > 0


@pytest.fixture(scope="module")
def exact_run(tmp_path_factory):
    request = ScenarioRequest("lattice", sample=0.2, seed=4, params=(("dt_s", 30.0),))
    spec = RunSpec.of(request, ["mb", "hindsight", "exact", "bound"], oracle_preset="matching")
    outcome = run_comparison(spec, tmp_path_factory.mktemp("exact") / "run", progress=False)
    folder, table = outcome.folder, outcome.table
    return folder, table


def test_the_simulator_realises_the_plan_and_the_checker_verifies_it(exact_run):
    folder, table = exact_run
    checks = {rc.run: rc for rc in check_folder(folder)}
    assert all(rc.ok for rc in checks.values()), {k: v.violations for k, v in checks.items() if not v.ok}
    assert checks["exact"].checked["exact_pairs"] > 0
    plan = json.loads((folder / "runs" / "exact" / "exact-plan" / "plan.json").read_text())
    assert plan["status"] == "optimal"
    assert table.loc["total_saving_km", "exact"] * 1000 == pytest.approx(plan["objective_m"], abs=1e-6)
    saving = table.loc["total_saving_km"]
    assert saving["mb"] <= saving["hindsight"] + 1e-9 <= saving["exact"] + 2e-9 <= saving["bound"] + 3e-9


def _copy(folder, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    return copy


def _rewrite_plan(folder, edit) -> None:
    """Edit the plan and record the edited plan's digest, as a forger would."""
    path = folder / "runs" / "exact" / "exact-plan" / "plan.json"
    plan = json.loads(path.read_text())
    edit(plan)
    path.write_text(json.dumps(plan))
    meta = json.loads((folder / "meta.json").read_text())
    meta["runs"]["exact"]["artefacts"]["exact-plan"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (folder / "meta.json").write_text(json.dumps(meta))


def test_an_edited_plan_fails_by_name(exact_run, tmp_path):
    folder = _copy(exact_run[0], tmp_path)
    path = folder / "runs" / "exact" / "exact-plan" / "plan.json"
    path.write_text(path.read_text().replace('"optimal"', '"optimal" '))
    assert "SHA-256 differs" in " ".join(run_violations(folder)["exact-optimum"])


def test_a_plan_claiming_more_than_the_run_realised_fails_by_name(exact_run, tmp_path):
    folder = _copy(exact_run[0], tmp_path)

    def inflate(plan):
        plan["objective_blocks"] += 1
        plan["objective_m"] += plan["block_m"]
        plan["bound_blocks"] += 1
        plan["pairs"][0][2] += plan["block_m"]

    _rewrite_plan(folder, inflate)
    assert any("the plan's proven optimum" in m for m in run_violations(folder)["exact-optimum"])


def test_an_unproven_plan_fails_by_name(exact_run, tmp_path):
    folder = _copy(exact_run[0], tmp_path)
    _rewrite_plan(folder, lambda plan: plan.update(status="time_limit", bound_blocks=plan["bound_blocks"] + 5))
    assert any("not proven optimal" in m for m in run_violations(folder)["exact-optimum"])


def test_a_plan_of_other_pairs_fails_by_name(exact_run, tmp_path):
    folder = _copy(exact_run[0], tmp_path)
    _rewrite_plan(folder, lambda plan: plan["pairs"][0].__setitem__(1, plan["pairs"][0][1] + 1))
    assert any("not in the plan" in m for m in run_violations(folder)["exact-optimum"])


@pytest.mark.slow
@pytest.mark.parametrize(
    "seed, sample, overrides",
    [
        (10, 0.15, {"dt_s": 30.0}),
        (11, 0.2, {"dt_s": 30.0, "max_pickup_m": 1000.0, "max_detour_m": 750.0}),
        (12, 0.2, {"dt_s": 30.0, "vehicles_per_100_orders": 15.0}),
        (13, 0.15, {"dt_s": 20.0, "patience_mean_s": 150.0, "planner_patience_s": 150.0}),
        (14, 0.1, {}),
    ],
)
def test_every_strategy_saves_at_most_opt_and_opt_at_most_the_bound(tmp_path, seed, sample, overrides):
    """The property behind the bracket: on random small lattice cities, every run (online strategies and the
    clairvoyant FL-perfect and hindsight) saves at most OPT, OPT is realised and checked, and OPT <= U; the
    folder's best known schedule saves OPT."""
    request = ScenarioRequest("lattice", sample=sample, seed=seed, params=tuple(overrides.items()))
    spec = RunSpec.of(request, [*ONLINE, "fl-perfect", "hindsight", "exact", "bound"], oracle_preset="matching")
    outcome = run_comparison(spec, tmp_path / "r", progress=False)
    folder, table = outcome.folder, outcome.table
    checks = {rc.run: rc for rc in check_folder(folder)}
    assert all(rc.ok for rc in checks.values()), {k: v.violations for k, v in checks.items() if not v.ok}
    saving = table.loc["total_saving_km"]
    opt, bound = saving["exact"], saving["bound"]
    assert opt > 0
    for run in [*ONLINE, "fl-perfect", "hindsight"]:
        assert saving[run] <= opt + 1e-9, run
    assert opt <= bound + 1e-9
    assert pd.notna(table.loc["total_saving_km"]).all()
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["best_known"]["saving_km"] == pytest.approx(opt)  # OPT's run, or another run that ties it
