"""One comparison: typed options recorded as run, calibration read off the strategy classes, runs shared."""

from __future__ import annotations

import json

import pytest

from rpbench.exceptions import ParameterError
from rpbench.harness import comparison
from rpbench.harness.comparison import parse_run_options, parse_strategies, run_comparison
from rpbench.scenarios import ScenarioRequest
from rpbench.strategies.forward import ForwardOptions


@pytest.fixture(scope="module")
def toy_request():
    return ScenarioRequest("toy", sample=0.1, seed=4)


def test_fl_is_calibrated_by_one_mb_run_shared_with_the_mb_column(toy_request, tmp_path, monkeypatch):
    calls = []
    real = comparison.simulate_strategy

    def counting(scenario, name, preset, **kw):
        calls.append((name, kw.get("options")))
        return real(scenario, name, preset, **kw)

    monkeypatch.setattr(comparison, "simulate_strategy", counting)
    folder, table = run_comparison(
        toy_request.build(), ["fl", "mb"], "highs", out=tmp_path / "r", progress=False, request=toy_request
    )
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
        lambda sc, name, preset, **kw: calls.append(name) or real(sc, name, preset, **kw),
    )
    options = parse_run_options(["fl.tau0_s=60", "mb.order_rule=min_then_check"], ["mb", "fl"])
    run_comparison(
        toy_request.build(),
        ["mb", "fl"],
        "highs",
        out=tmp_path / "r",
        run_options=options,
        progress=False,
        request=toy_request,
    )
    # MB with options is not the default calibration run: MB(options), MB(default) for l̄, FL
    assert calls == ["mb", "mb", "fl"]


def test_fully_specified_fl_needs_no_calibration(toy_request, tmp_path, monkeypatch):
    calls = []
    real = comparison.simulate_strategy
    monkeypatch.setattr(
        comparison,
        "simulate_strategy",
        lambda sc, name, preset, **kw: calls.append(name) or real(sc, name, preset, **kw),
    )
    options = parse_run_options(["fl.tau0_s=60", "fl.mean_pickup_m=500"], ["fl"])
    run_comparison(toy_request.build(), ["fl"], "highs", out=tmp_path / "r", run_options=options, progress=False)
    assert calls == ["fl"]


def test_strategy_list_is_checked():
    assert parse_strategies("MB, fl ,oracle1") == ["mb", "fl", "oracle1"]
    with pytest.raises(ParameterError, match="unknown strategy 'fx'"):
        parse_strategies("mb,fx")
    with pytest.raises(ParameterError, match="names a strategy twice"):
        parse_strategies("mb,mb")
