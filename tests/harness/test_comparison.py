"""One comparison: typed options recorded as run, calibration read off the strategy classes, runs shared."""

from __future__ import annotations

import json

import pytest

from rpbench.harness import comparison
from rpbench.harness.comparison import run_comparison
from rpbench.harness.spec import RunSpec
from rpbench.scenarios import ScenarioRequest
from rpbench.strategies.forward import ForwardOptions


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
    folder, table = run_comparison(RunSpec.of(toy_request, ["fl", "mb"]), tmp_path / "r", progress=False)
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
    from rpbench.harness.comparison import run_comparison
    from rpbench.harness.spec import RunSpec
    from rpbench.results.check import check_folder
    from rpbench.results.plots import run_colors
    from rpbench.results.runs import run_styles
    from rpbench.results.store import read_meta
    from rpbench.scenarios import ScenarioRequest

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=2), ["fl", "fl@tau0_s=30", "fl@tau0_s=600"])
    folder, table = run_comparison(spec, tmp_path / "variants", progress=False)
    meta = read_meta(folder)
    assert [meta["runs"][r]["options"]["tau0_s"] for r in ("fl@tau0_s=30", "fl@tau0_s=600")] == [30.0, 600.0]
    assert meta["runs"]["fl@tau0_s=30"]["label"] == "FL (tau0_s=30)"
    colors = run_colors(list(meta["runs"]), run_styles(meta))
    assert len(set(colors.values())) == 3
    assert (folder / "runs" / "fl@tau0_s=600" / "events.csv.gz").is_file()
    assert all(rc.ok for rc in check_folder(folder))
    assert "FL (tau0_s=600)" in (folder / "report.md").read_text()
