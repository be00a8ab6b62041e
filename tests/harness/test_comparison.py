"""One comparison: typed options recorded as run, calibration read off the strategy classes, runs shared."""

from __future__ import annotations

import dataclasses
import json

import pandas as pd
import pytest

from rpbench.check import check_folder
from rpbench.harness import comparison, sidecar
from rpbench.harness.comparison import run_comparison
from rpbench.results.metrics import TIMING_KPIS
from rpbench.results.read import over_budget_runs
from rpbench.results.store import read_meta
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec
from rpbench.strategies.forward import ForwardOptions


@pytest.fixture(autouse=True)
def in_one_process(monkeypatch):
    """The tests here count the simulations this process makes: no second process takes a run."""
    monkeypatch.setattr(sidecar, "idle_core", lambda: False)


@pytest.fixture(scope="module")
def toy_request():
    return ScenarioRequest("toy", sample=0.1, seed=4)


def test_fl_is_calibrated_by_one_mb_run_shared_with_the_mb_column(toy_request, tmp_path, monkeypatch):
    calls = []
    real = comparison.simulate_strategy

    def counting(scenario, entry, preset, **kw):
        calls.append((entry.name, entry.options))
        return real(scenario, entry, preset, **kw)

    monkeypatch.setattr(comparison, "simulate_strategy", counting)
    outcome = run_comparison(RunSpec.of(toy_request, ["fl", "mb"]), tmp_path / "r", progress=False)
    folder, table = outcome.folder, outcome.table
    assert [name for name, _ in calls] == ["mb", "fl"]  # the calibration run is the MB column
    fl_options = calls[1][1]
    mb = table["mb"]
    assert fl_options.tau0_s == pytest.approx(mb["avg_pickup_time_s"])
    assert fl_options.mean_pickup_m == pytest.approx(mb["avg_pickup_distance_m"])
    meta = json.loads((folder / "meta.json").read_text())
    recorded = meta["runs"]["fl"]["options"]
    assert recorded["tau0_s"] == pytest.approx(fl_options.tau0_s) and recorded["rates"] == "auto"
    assert set(recorded) == set(ForwardOptions().as_dict())  # every option, defaults included
    assert meta["scenario"]["args"] == toy_request.meta()


def test_user_options_are_kept_and_an_mb_column_with_options_is_its_own_run(toy_request, tmp_path, monkeypatch):
    calls = []
    real = comparison.simulate_strategy
    monkeypatch.setattr(
        comparison,
        "simulate_strategy",
        lambda sc, entry, preset, **kw: calls.append(entry.name) or real(sc, entry, preset, **kw),
    )
    options = {"fl": {"tau0_s": "60"}, "mb": {"order_rule": "min_then_check"}}
    run_comparison(RunSpec.of(toy_request, ["mb", "fl"], options=options), tmp_path / "r", progress=False)
    # MB with options is not the default calibration run: MB(options), MB(default) for l̄, FL
    assert calls == ["mb", "mb", "fl"]


def test_fully_specified_fl_needs_no_calibration(toy_request, tmp_path, monkeypatch):
    calls = []
    real = comparison.simulate_strategy
    monkeypatch.setattr(
        comparison,
        "simulate_strategy",
        lambda sc, entry, preset, **kw: calls.append(entry.name) or real(sc, entry, preset, **kw),
    )
    spec = RunSpec.of(toy_request, ["fl"], options={"fl": {"tau0_s": 60.0, "mean_pickup_m": 500.0}})
    run_comparison(spec, tmp_path / "r", progress=False)
    assert calls == ["fl"]


def test_two_variants_of_one_strategy_in_one_run(tmp_path):
    """Each variant is simulated with its own options, labelled and coloured apart, and checked."""
    from rpbench.check import check_folder
    from rpbench.harness.comparison import run_comparison
    from rpbench.report.plots import run_colors
    from rpbench.results.runs import run_styles
    from rpbench.results.store import read_meta
    from rpbench.scenarios import ScenarioRequest
    from rpbench.spec import RunSpec

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=2), ["fl", "fl@tau0_s=30", "fl@tau0_s=600"])
    folder = run_comparison(spec, tmp_path / "variants", progress=False).folder
    meta = read_meta(folder)
    assert [meta["runs"][r]["options"]["tau0_s"] for r in ("fl@tau0_s=30", "fl@tau0_s=600")] == [30.0, 600.0]
    assert meta["runs"]["fl@tau0_s=30"]["label"] == "FL (tau0_s=30)"
    colors = run_colors(list(meta["runs"]), run_styles(meta))
    assert len(set(colors.values())) == 3
    assert (folder / "runs" / "fl@tau0_s=600" / "events.csv.gz").is_file()
    assert all(rc.ok for rc in check_folder(folder))
    assert "FL (tau0_s=600)" in (folder / "report.md").read_text()


# ------------------------------------------------------------------ decision budget
@pytest.fixture(scope="module")
def budget_folders(tmp_path_factory):
    """The same comparison without a budget, with a budget no round meets and with one every round meets."""
    root = tmp_path_factory.mktemp("budget")
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=4), ["mb", "fl", "oracle1"])
    specs = {budget: dataclasses.replace(spec, decision_budget_s=budget) for budget in (None, 1e-9, 86400.0)}
    return {budget: run_comparison(s, root / str(budget), progress=False).folder for budget, s in specs.items()}


def test_a_tiny_budget_flags_every_solved_round_and_a_huge_one_none(budget_folders):
    """Every round in rounds.csv.gz was solved; the KPI counts its run's flags; the folder checks clean."""
    for budget, flagged in ((1e-9, True), (86400.0, False)):
        folder = budget_folders[budget]
        rounds = pd.read_csv(folder / "rounds.csv.gz")
        assert rounds["over_budget"].dtype == bool and (rounds["over_budget"] == flagged).all()
        kpis = pd.read_csv(folder / "kpis.csv").set_index(["run", "kpi"])["value"]
        for run in ("mb", "fl"):
            assert kpis[(run, "rounds_over_budget")] == (rounds["run"] == run).sum() * flagged
        assert ("oracle1", "rounds_over_budget") not in kpis.index  # an offline run has no rounds
        assert read_meta(folder)["decision_budget_s"] == budget
        assert all(rc.ok for rc in check_folder(folder))
    report = (budget_folders[1e-9] / "report.md").read_text()
    assert "rounds > budget (1e-09 s)" in report and "Decision budget 1e-09 s" in report


def test_without_a_budget_nothing_is_added_and_a_budget_changes_no_simulation(budget_folders):
    plain = budget_folders[None]
    assert "decision_budget_s" not in read_meta(plain)
    assert "over_budget" not in pd.read_csv(plain / "rounds.csv.gz").columns
    assert "rounds_over_budget" not in set(pd.read_csv(plain / "kpis.csv")["kpi"])
    assert "budget" not in (plain / "report.md").read_text()
    assert over_budget_runs(plain) == {}
    for budget in (1e-9, 86400.0):
        for run in ("mb", "fl"):
            log = f"runs/{run}/events.csv.gz"
            assert pd.read_csv(budget_folders[budget] / log).equals(pd.read_csv(plain / log))
        kpis = pd.read_csv(budget_folders[budget] / "kpis.csv")
        same = kpis[~kpis["kpi"].isin(TIMING_KPIS)].reset_index(drop=True)
        before = pd.read_csv(plain / "kpis.csv")
        assert same.equals(before[~before["kpi"].isin(TIMING_KPIS)].reset_index(drop=True))


def test_the_note_names_each_run_with_rounds_over_the_budget(budget_folders):
    notes = over_budget_runs(budget_folders[1e-9])
    rounds = pd.read_csv(budget_folders[1e-9] / "rounds.csv.gz")
    assert list(notes) == ["mb", "fl"]
    n = int((rounds["run"] == "mb").sum())
    assert notes["mb"].startswith(f"{n} of {n} rounds decided slower than the 1e-09 s budget (slowest ")
    assert over_budget_runs(budget_folders[86400.0]) == {}


@pytest.mark.parametrize(
    ("runs", "options", "movable"),
    [
        # MB calibrates FL and FL-no_delay: neither they nor MB may move; NP, RTV and Hindsight may
        (["np", "mb", "rtv", "fl-nd", "fl", "hindsight"], {}, ["np", "rtv", "hindsight"]),
        # a fully specified FL needs no MB run: both may move
        (["mb", "fl"], {"fl": {"tau0_s": 60.0, "mean_pickup_m": 500.0}}, ["mb", "fl"]),
        # two runs of MB with other options: each its own simulation, both may move
        (["mb", "mb@order_rule=min_then_check", "np"], {}, ["mb", "mb@order_rule=min_then_check", "np"]),
        # two runs of MB with the same options: the parent shares one simulation, so neither moves
        (["mb", "mb@order_rule=min_feasible", "np"], {}, ["np"]),
    ],
)
def test_independent_runs_need_nothing_from_another(runs, options, movable):
    spec = RunSpec.of(ScenarioRequest("toy"), runs, options=options)
    assert [spec.simulated[i].name for i in comparison.independent_runs(spec)] == movable
