"""One prediction per scenario hour: slim results for the dispatcher, warm starts, shared equal hours."""

from __future__ import annotations

import numpy as np

from rpbench.predict import PredictConfig, predict, scenario_predictions
from rpbench.predict.prediction import cached_prediction
from rpbench.scenarios.registry import build_scenario


def test_hours_are_slim_and_equal_hours_are_shared(tmp_path, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    scenario = build_scenario("toy", sample=1.0, seed=0)
    preds = scenario_predictions(scenario, "scenario", np.array([60.0, 60.0]), PredictConfig())
    assert len(preds) == 2
    for pred in preds:
        assert len(pred.rho) == 0 and len(pred.od.e_taker) == 0  # per-state arrays dropped
        assert len(pred.od.pairing_prob) == len(pred.rates)  # per-OD values kept
    full = cached_prediction(scenario.network, preds[0].rates, scenario.params, PredictConfig(tau0_s=60.0))
    assert len(full.rho) > 0
    look_full = full.lookup(full.rates.origin, full.rates.destination)
    look_slim = preds[0].lookup(full.rates.origin, full.rates.destination)
    for a, b in zip(look_full.__dict__.values(), look_slim.__dict__.values(), strict=True):
        np.testing.assert_array_equal(a, b)


def test_an_hour_is_solved_and_cached_by_predict(tmp_path, monkeypatch):
    """The hours FL solves go through :func:`predict`: the same cache entry, with its timing facts."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    scenario = build_scenario("toy", sample=1.0, seed=0)
    (hour,) = scenario_predictions(scenario, "scenario", np.array([60.0]), PredictConfig())
    config = PredictConfig(tau0_s=60.0)
    stored = cached_prediction(scenario.network, hour.rates, scenario.params, config)
    assert stored is not None and {"time_s", "cpu_s", "peak_rss_mb"} <= set(stored.info)
    again = predict(scenario.network, hour.rates, scenario.params, config)
    assert again.from_cache
    fresh = predict(scenario.network, hour.rates, scenario.params, config, use_cache=False)
    assert not fresh.from_cache
    for name, value in fresh.arrays()[0].items():
        np.testing.assert_array_equal(again.arrays()[0][name], value, err_msg=name)
