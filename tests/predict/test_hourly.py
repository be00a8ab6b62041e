"""One prediction per scenario hour: slim results for the dispatcher, cached lean, shared equal hours, the same
values solved here or in worker processes; the rates an online FL reads (the demand known before the day, never
the day's own orders)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import line_network, scenario_of

from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.predict import PredictConfig, predict, scenario_predictions
from rpbench.predict.hourly import hourly_rates, rate_source, reads_realised_orders
from rpbench.predict.pool import solve_predictions
from rpbench.predict.prediction import cached_prediction
from rpbench.scenarios.base import Demand
from rpbench.scenarios.registry import build_scenario


def test_hours_are_slim_and_equal_hours_are_shared(tmp_path, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    scenario = build_scenario("toy", sample=1.0, seed=0)
    preds = scenario_predictions(scenario, "scenario", np.array([60.0, 60.0]), PredictConfig(), workers=1)
    assert len(preds) == 2
    for pred in preds:
        assert len(pred.rho) == 0 and len(pred.od.e_taker) == 0  # per-state arrays dropped
        assert len(pred.od.pairing_prob) == len(pred.rates)  # per-OD values kept
    config = PredictConfig(tau0_s=60.0)
    full = predict(scenario.network, preds[0].rates, scenario.params, config, use_cache=False)
    look_full = full.lookup(full.rates.origin, full.rates.destination)
    look_slim = preds[0].lookup(full.rates.origin, full.rates.destination)
    for a, b in zip(look_full.__dict__.values(), look_slim.__dict__.values(), strict=True):
        np.testing.assert_array_equal(a, b)


def test_an_hour_is_solved_and_cached_lean_by_predict(tmp_path, monkeypatch):
    """The hours FL solves go through :func:`predict` and are cached lean (per-OD arrays, timing facts): a slim
    read finds them, a full read solves the prediction again and caches it in full."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    scenario = build_scenario("toy", sample=1.0, seed=0)
    (hour,) = scenario_predictions(scenario, "scenario", np.array([60.0]), PredictConfig(), workers=1)
    assert hour.lean and not hour.from_cache
    config = PredictConfig(tau0_s=60.0)
    stored = cached_prediction(scenario.network, hour.rates, scenario.params, config, slim=True)
    assert stored is not None and stored.lean and {"time_s", "cpu_s", "peak_rss_mb"} <= set(stored.info)
    assert cached_prediction(scenario.network, hour.rates, scenario.params, config) is None  # no per-state arrays
    again = predict(scenario.network, hour.rates, scenario.params, config)
    assert not again.from_cache and not again.lean and len(again.rho) > 0
    cached = predict(scenario.network, hour.rates, scenario.params, config)
    assert cached.from_cache and len(cached.rho) == len(again.rho)
    for name, value in hour.arrays()[0].items():
        np.testing.assert_array_equal(cached.arrays()[0][name], value, err_msg=name)


def test_chains_solved_in_worker_processes_equal_the_serial_ones(tmp_path, monkeypatch):
    """Chains are solved from their own inputs only: two workers give the serial values bit for bit; within a
    chain each prediction is warm-started from the one before (fewer sweeps, the same fixed point)."""
    scenario = build_scenario("toy", sample=1.0, seed=0)
    (rates,) = hourly_rates(scenario.online_view(), "auto", 1)
    chains = [[(rates, PredictConfig(tau0_s=t)) for t in (60.0, 70.0)], [(rates, PredictConfig(tau0_s=120.0))]]

    def solve(cache: str, workers: int, todo=chains):
        monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / cache))
        return solve_predictions(scenario.network, scenario.params, todo, workers)

    serial, pooled = solve("serial", 1), solve("pooled", 2)
    assert len(serial) == 3 and not any(p.from_cache for p in serial + pooled)
    assert all(p.lean and len(p.rho) == 0 for p in pooled)
    for a, b in zip(serial, pooled, strict=True):
        for name, value in a.arrays()[0].items():
            np.testing.assert_array_equal(b.arrays()[0][name], value, err_msg=name)
    cold = solve("cold", 1, [chains[0][1:]])[0]  # the chain's second prediction from rho = 0
    assert serial[1].info["iterations"] < cold.info["iterations"]
    np.testing.assert_allclose(serial[1].od.e_vacant, cold.od.e_vacant, rtol=1e-6, atol=1e-6)
    assert all(p.from_cache for p in solve("pooled", 2))


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
