"""One prediction per scenario hour: slim results for the dispatcher, warm starts, shared equal hours; the rates
an online FL reads (the demand known before the day, never the day's own orders)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import line_network, scenario_of

from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.predict import PredictConfig, predict, scenario_predictions
from rpbench.predict.hourly import hourly_rates, rate_source, reads_realised_orders
from rpbench.predict.prediction import cached_prediction
from rpbench.scenarios.base import Demand
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


def moved_destination(scenario):
    """``scenario`` with its first order's destination changed after the fact."""
    o = scenario.orders
    destination = o.destination.copy()
    destination[0] = (destination[0] + 1) % scenario.network.n_nodes
    return dataclasses.replace(scenario, orders=dataclasses.replace(o, destination=destination))


def same_rates(a, b) -> bool:
    return all(
        np.array_equal(getattr(x, f), getattr(y, f))
        for x, y in zip(a, b, strict=True)
        for f in ("origin", "destination", "rate_per_s")
    )


def test_toy_rates_come_from_its_history_not_from_its_orders():
    """``auto`` on the toy city reads its generator's past days: an order changed after the fact changes nothing
    (counting the day's own orders, ``scenario``, it does)."""
    toy = build_scenario("toy", sample=0.3, seed=2)
    moved = moved_destination(toy)
    rates = hourly_rates(toy.online_view(), "auto", 1)
    assert same_rates(rates, hourly_rates(moved.online_view(), "auto", 1))
    assert same_rates(rates, hourly_rates(toy.online_view(), "history", 1))
    assert not same_rates(hourly_rates(toy, "scenario", 1), hourly_rates(moved, "scenario", 1))
    # the mean of its ten past days: each carries the hour's 120 orders
    assert rates[0].total_per_s == pytest.approx(120 / 3600.0)
    assert "past days" in rates[0].source


def test_an_online_view_cannot_count_its_own_orders():
    view = build_scenario("toy", sample=0.3, seed=2).online_view("strategy 'fl' (rpbench.strategies.forward.X)")
    with pytest.raises(LookaheadError, match=r"^strategy 'fl' .*: FL rates 'scenario' count the scenario's own"):
        hourly_rates(view, "scenario", 1)


@pytest.mark.parametrize(
    "demand, auto",
    [
        (Demand(table="month", data_dir="d"), "month"),
        (build_scenario("toy", sample=0.1).demand, "history"),
        (Demand(data_dir="d"), "scenario"),  # no history (the 2017-07-01 trace): the realisation
    ],
)
def test_auto_reads_the_history_a_scenario_carries(demand, auto):
    assert rate_source("auto", demand) == auto
    assert reads_realised_orders("auto", demand) == (auto == "scenario")
    assert reads_realised_orders("scenario", demand) and not reads_realised_orders("month", demand)
    with pytest.raises(ParameterError, match="rates 'weekly' unknown"):
        rate_source("weekly", demand)


def test_history_rates_need_a_history():
    with pytest.raises(ParameterError, match="FL rates 'history': scenario 'hand-made' has no demand history"):
        hourly_rates(scenario_of(line_network(4), [(0.0, 0, 3)], [1]).online_view(), "history", 1)
