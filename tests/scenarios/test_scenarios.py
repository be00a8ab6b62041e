"""Scenario generators: sizes, sampling and fleet rules, determinism, bad parameters."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.exceptions import DataNotFoundError, ParameterError
from rpbench.scenarios import build_scenario
from rpbench.scenarios.base import Params


def _same(a, b) -> bool:
    return all(
        np.array_equal(getattr(a.orders, f), getattr(b.orders, f))
        for f in ("order_id", "request_s", "origin", "destination", "patience_s")
    ) and np.array_equal(a.fleet.initial_node, b.fleet.initial_node)


def test_peak_default_sample(data_dir):
    s = build_scenario("haikou-peak", data_dir=data_dir)
    assert len(s.orders) == round(0.3 * 2018) == 605
    assert len(s.fleet) == 151  # 25 per 100 sampled orders
    assert s.network.n_nodes == 3901
    assert set(s.fleet.initial_node) <= set(s.orders.origin)
    assert (s.orders.patience_s >= 30).all()
    assert s.orders.request_s.min() >= 0 and s.orders.request_s.max() < 3600
    assert not s.synthetic


def test_peak_full_hour_and_random_nodes(data_dir):
    s = build_scenario("haikou-peak", data_dir=data_dir, sample=1.0, fleet_placement="random_nodes")
    assert len(s.orders) == 2018 and len(s.fleet) == 504


def test_peak_is_deterministic(data_dir):
    a = build_scenario("haikou-peak", data_dir=data_dir, seed=7)
    b = build_scenario("haikou-peak", data_dir=data_dir, seed=7)
    c = build_scenario("haikou-peak", data_dir=data_dir, seed=8)
    assert _same(a, b)
    assert not _same(a, c)


def test_fleet_placement_does_not_change_the_orders(data_dir):
    a = build_scenario("haikou-peak", data_dir=data_dir, seed=3)
    b = build_scenario("haikou-peak", data_dir=data_dir, seed=3, fleet_placement="random_nodes")
    assert np.array_equal(a.orders.order_id, b.orders.order_id)


def test_day_stand_in(data_dir):
    s = build_scenario("haikou-day", data_dir=data_dir, sample=1.0)
    assert len(s.orders) == 52124
    assert s.synthetic and "SYNTHETIC" in s.label
    hourly = np.bincount((s.orders.request_s // 3600).astype(int), minlength=24)
    assert hourly[8] == 1641
    assert s.fleet.on_duty(8 * 3600 + 1) == round(1641 * 0.25)


def test_trace(data_dir):
    s = build_scenario("haikou-trace", data_dir=data_dir)
    assert len(s.orders) == 18367 and s.network.n_nodes == 724


def test_toy_needs_no_data_and_is_deterministic():
    a = build_scenario("toy", seed=1)
    b = build_scenario("toy", seed=1)
    assert _same(a, b)
    assert len(a.orders) == 400 and len(a.fleet) == 100
    half = build_scenario("toy", sample=0.5)
    assert len(half.orders) == 200


def test_patience_distribution():
    s = build_scenario("toy", seed=0, params=Params(patience_sd_s=10.0))
    k = s.orders.patience_s
    assert abs(k.mean() - 90) < 3 and k.min() >= 30


@pytest.mark.parametrize("sample", [0.0, -0.1])
def test_sample_outside_unit_interval(sample):
    with pytest.raises(ParameterError, match="must lie in \\(0, 1\\]"):
        build_scenario("toy", sample=sample)


def test_toy_takes_no_demand_multiplier():
    """Only the synthetic day scales its volume (tests/scenarios/test_multiplier.py)."""
    with pytest.raises(ParameterError, match="--sample 1.5 is out of range \\(0 < value <= 1\\) for scenario 'toy'"):
        build_scenario("toy", sample=1.5)


@pytest.mark.parametrize(
    "name", ["dt_s", "planner_patience_s", "patience_mean_s", "max_pickup_m", "max_detour_m", "speed_mps"]
)
@pytest.mark.parametrize("value", [0.0, -5.0])
def test_non_positive_parameters(name, value):
    with pytest.raises(ParameterError, match=f"{name} = .* must be > 0"):
        build_scenario("toy", param_overrides={name: value})


def test_unknown_parameter_and_scenario():
    with pytest.raises(ParameterError, match="unknown parameter"):
        Params().replace(delta_t=3)
    with pytest.raises(ParameterError, match="unknown scenario"):
        build_scenario("new-york")


def test_missing_data_folder(monkeypatch, tmp_path):
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    monkeypatch.setattr("rpbench.files.paths.default_data_candidates", lambda: [tmp_path / "nothing"])
    with pytest.raises(DataNotFoundError, match="no Haikou data folder found"):
        build_scenario("haikou-peak")


def test_explicit_missing_folder():
    with pytest.raises(DataNotFoundError, match="does not exist"):
        build_scenario("haikou-peak", data_dir="/no/such/folder")


def test_unknown_node_in_orders(fake_data):
    import gzip

    path = fake_data / "demand_0800_0900" / "orders" / "2017-05-01.csv.gz"
    with gzip.open(path, "rt") as fh:
        lines = fh.read().splitlines()
    parts = lines[1].split(",")
    parts[6] = "4242"  # origin_id
    lines[1] = ",".join(parts)
    with gzip.open(path, "wt") as fh:
        fh.write("\n".join(lines) + "\n")
    with pytest.raises(Exception, match="origin node id in the 2017-05-01 orders 4242 is not a node"):
        build_scenario("haikou-peak", data_dir=fake_data, sample=1.0)
