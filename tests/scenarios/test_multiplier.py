"""``--sample k > 1`` on the synthetic day: k times the volume drawn anew, the fleet by the same rule, a
fraction unchanged, and scenarios of real orders (or a fixed-volume generator) refusing it.

The day is built on the tiny fake Haikou folder (10 orders an hour, 9 equally likely ODs); one test reads
the real folder (``haikou`` marker) for the stress day's own figures.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from rpbench.exceptions import ParameterError
from rpbench.scenarios import SCENARIOS, ScenarioRequest, build_scenario
from rpbench.scenarios.base import Params
from rpbench.scenarios.common import MAX_DEMAND_MULTIPLIER, check_sample, fleet_size
from rpbench.scenarios.day import build_day
from rpbench.scenarios.peak import build_peak

#: The fake folder's day: 10 orders in each of the 24 hours.
FAKE_HOURLY = np.full(24, 10)
#: Standard deviations a count may stray from its mean: the chance of a miss is below 1e-8 per count.
SIGMAS = 6.0


def _digest(s) -> str:
    h = hashlib.sha256()
    for a in (s.orders.order_id, s.orders.request_s, s.orders.origin, s.orders.destination, s.orders.patience_s):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(np.ascontiguousarray(s.fleet.initial_node).tobytes())
    if s.fleet.online_count is not None:
        h.update(np.ascontiguousarray(s.fleet.online_count).tobytes())
    return h.hexdigest()[:16]


@pytest.mark.parametrize("k", [2.0, 4.0, 7.5])
def test_the_order_count_scales_as_a_poisson_volume_of_k_times(fake_data, k):
    s = build_scenario("haikou-day", data_dir=fake_data, sample=k, seed=11)
    hour = (s.orders.request_s // 3600).astype(int)
    assert np.array_equal(np.bincount(hour, minlength=24), np.round(k * FAKE_HOURLY))  # each hour k times its own
    mean = k * FAKE_HOURLY.sum()  # the Poisson volume k·λ of the day
    assert abs(len(s.orders) - mean) <= SIGMAS * np.sqrt(mean)
    assert s.synthetic and "SYNTHETIC" in s.label and f"DEMAND x{k:g}" in s.label
    assert s.provenance["sample"] == k
    assert s.demand.orders_per_hour == tuple(float(n) for n in np.round(k * FAKE_HOURLY))  # what FL predicts from


def test_the_k_times_day_is_drawn_anew_not_copied(fake_data):
    """Within each hour the k·n requests are uniform (a Poisson process given the hour's count) and their ODs
    follow the table: counts per ten-minute window and per OD lie within SIGMAS standard deviations of their
    binomial means, and no request repeats another's time (copies of the day would)."""
    k = 4.0
    s = build_scenario("haikou-day", data_dir=fake_data, sample=k, seed=3)
    n = len(s.orders)
    assert len(np.unique(s.orders.request_s)) == n
    one = build_scenario("haikou-day", data_dir=fake_data, sample=1.0, seed=3)
    assert n == 4 * len(one.orders)
    windows = np.bincount((s.orders.request_s % 3600 // 600).astype(int), minlength=6)
    p = 1 / 6
    assert np.all(np.abs(windows - n * p) <= SIGMAS * np.sqrt(n * p * (1 - p))), windows
    pairs, counts = np.unique(np.stack([s.orders.origin, s.orders.destination]), axis=1, return_counts=True)
    assert pairs.shape[1] == 9  # the fake table's nine ODs, equally likely
    p = 1 / 9
    assert np.all(np.abs(counts - n * p) <= SIGMAS * np.sqrt(n * p * (1 - p))), counts


def test_the_fleet_follows_the_hourly_counts_by_the_same_ratio(fake_data):
    params = Params()
    for k in (1.0, 4.0, 10.0):
        s = build_scenario("haikou-day", data_dir=fake_data, sample=k, seed=0)
        per_hour = np.round(k * FAKE_HOURLY)
        expected = [fleet_size(int(n), params) for n in per_hour]
        assert s.fleet.online_count.tolist() == expected
        assert len(s.fleet) == max(expected)
    assert build_scenario("haikou-day", data_dir=fake_data, sample=4.0).fleet.online_count[0] == 10  # 25 per 100
    ratio = build_scenario(
        "haikou-day", data_dir=fake_data, sample=4.0, param_overrides={"vehicles_per_100_orders": 50}
    )
    assert ratio.fleet.online_count[0] == 20


def test_the_k_times_day_is_reproducible_from_its_seed(fake_data):
    a, b = (build_scenario("haikou-day", data_dir=fake_data, sample=3.0, seed=9) for _ in range(2))
    c = build_scenario("haikou-day", data_dir=fake_data, sample=3.0, seed=10)
    assert _digest(a) == _digest(b) != _digest(c)


# The arrays each scenario gave before the multiplier existed (the same digest, computed on the commit
# before it): a fraction keeps its orders, fleet and label.
UNCHANGED = [
    ("haikou-day", 0.3, 0, 72, 1, "f9cb8e53301990e1", "(30 % of 240 orders, seed 0)"),
    ("haikou-day", 1.0, 5, 240, 2, "9937403a8da6e70f", "(100 % of 240 orders, seed 5)"),
    ("toy", 0.5, 0, 200, 50, "1e72944b0f233d9e", "200 orders in one hour, seed 0"),
    ("toy", 1.0, 3, 400, 100, "2523aaf0322cb7d8", "400 orders in one hour, seed 3"),
    ("lattice", 0.3, 1, 30, 8, "d4aaeeaa4efc365b", "30 orders in 30 min, seed 1"),
]


@pytest.mark.parametrize("name, sample, seed, orders, vehicles, digest, label", UNCHANGED)
def test_a_fraction_gives_the_orders_it_always_gave(fake_data, name, sample, seed, orders, vehicles, digest, label):
    s = build_scenario(name, data_dir=fake_data, sample=sample, seed=seed)
    assert (len(s.orders), len(s.fleet), _digest(s)) == (orders, vehicles, digest)
    assert label in s.label


REAL = ["haikou-peak", "haikou-paper-input", "haikou-trace", "city", "manhattan-peak", "manhattan-day"]


@pytest.mark.parametrize("name", REAL)
def test_a_scenario_of_real_orders_refuses_a_multiplier(name):
    """Before any data folder is looked for (none is given): the request itself is refused."""
    message = f"--sample 1.5 is out of range \\(0 < value <= 1\\) for scenario '{name}': its orders are real"
    with pytest.raises(ParameterError, match=message):
        ScenarioRequest(name, sample=1.5)
    with pytest.raises(ParameterError, match=message):
        build_scenario(name, sample=1.5, city="nowhere" if name == "city" else None)


def test_the_builders_refuse_it_when_called_directly(fake_data):
    with pytest.raises(ParameterError, match="for scenario 'haikou-peak': its orders are real"):
        build_peak(fake_data, sample=2.0)
    assert len(build_day(fake_data, sample=2.0).orders) == 480


@pytest.mark.parametrize("name", ["toy", "lattice"])
def test_a_fixed_volume_generator_refuses_it(name):
    with pytest.raises(ParameterError, match=f"for scenario '{name}': its generator draws a fixed volume"):
        build_scenario(name, sample=1.5)


def test_which_scenarios_take_a_multiplier():
    takes = {name for name, spec in SCENARIOS.items() if spec.max_sample > 1}
    assert takes == {"haikou-day"}
    assert all(not SCENARIOS[name].real_orders for name in takes)
    assert set(REAL) == {name for name, spec in SCENARIOS.items() if spec.real_orders}


@pytest.mark.parametrize("sample", [0.0, -0.1, float("nan"), float("inf"), MAX_DEMAND_MULTIPLIER + 1, "2"])
def test_the_day_refuses_a_sample_outside_its_range(fake_data, sample):
    with pytest.raises(ParameterError, match="--sample"):
        build_scenario("haikou-day", data_dir=fake_data, sample=sample)


def test_check_sample_keeps_a_fraction_as_it_was():
    assert check_sample(0.3) == 0.3 and check_sample(1) == 1.0
    with pytest.raises(ParameterError, match="must lie in \\(0, 1\\]"):
        check_sample(0)
    with pytest.raises(ParameterError, match="out of range \\(0 < value <= 1\\): its orders are real"):
        check_sample(1.5)
    assert check_sample(4, scenario="haikou-day", most=MAX_DEMAND_MULTIPLIER, real=False) == 4.0


@pytest.mark.haikou
def test_the_four_times_day_of_haikou(data_dir):
    s = build_scenario("haikou-day", data_dir=data_dir, sample=4.0)
    one = build_scenario("haikou-day", data_dir=data_dir, sample=1.0)
    assert len(s.orders) == 4 * 52124 == 208_496
    hourly = np.bincount((s.orders.request_s // 3600).astype(int), minlength=24)
    assert hourly[8] == 4 * 1641
    assert len(s.fleet) == fleet_size(4 * int(np.max(one.provenance["orders_per_hour"])), s.params) == 3613
    assert s.fleet.on_duty(8 * 3600 + 1) == round(4 * 1641 * 0.25)
