"""OD rates: canonical order, merging, validation, and the Haikou sources (docs/algorithms.md §2.1)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.exceptions import DataError, DataNotFoundError, ParameterError
from rpbench.predict import (
    OdRates,
    day_table_rates,
    month_rates,
    order_rates,
    peak_order_rates,
    scenario_rates,
    table_rates,
)
from rpbench.scenarios import build_scenario
from rpbench.scenarios.common import haikou_network
from rpbench.scenarios.toy import grid_network


def test_from_arrays_sorts_and_merges_duplicates():
    r = OdRates.from_arrays([3, 1, 3, 0], [2, 5, 2, 4], [0.1, 0.2, 0.3, 0.4], [7, 8, 9, 10], n_nodes=6)
    assert r.origin.tolist() == [0, 1, 3] and r.destination.tolist() == [4, 5, 2]
    np.testing.assert_allclose(r.rate_per_s, [0.4, 0.2, 0.4])
    assert r.od_id.tolist() == [10, 8, 7]  # first id of a merged OD is kept


def test_bad_rates_are_one_clear_error():
    with pytest.raises(DataError, match="negative or not finite"):
        OdRates.from_arrays([0], [1], [-1.0], n_nodes=3)
    with pytest.raises(DataError, match="negative or not finite"):
        OdRates.from_arrays([0], [1], [np.nan], n_nodes=3)
    with pytest.raises(DataError, match="outside the network"):
        OdRates.from_arrays([0], [3], [1.0], n_nodes=3)
    with pytest.raises(ParameterError, match="sorted"):
        OdRates(np.array([1, 0], np.int32), np.array([0, 0], np.int32), np.ones(2), np.zeros(2, np.int64))


def test_order_rates_count_per_period():
    net = grid_network(3)
    r = order_rates(net, [0, 0, 1], [2, 2, 2], 3600.0, source="test")
    np.testing.assert_allclose(r.rate_per_s, [2 / 3600, 1 / 3600])
    with pytest.raises(ParameterError):
        order_rates(net, [0], [1], 0.0, source="test")


def test_scenario_rates_total_equals_orders_per_horizon():
    sc = build_scenario("toy", sample=0.5)
    r = scenario_rates(sc)
    assert r.total_per_s == pytest.approx(len(sc.orders) / sc.horizon_s)


def test_table_rates_rejects_negative_lambda(tmp_path):
    net = grid_network(3)
    path = tmp_path / "od.csv"
    path.write_text("OD_id,origin_id,destination_id,lambda\n0,0,1,0.5\n1,1,2,-0.1\n")
    with pytest.raises(DataError, match="negative rate"):
        table_rates(net, path)
    path.write_text("OD_id,origin_id,destination_id,lambda\n0,0,1,0.6\n")
    assert table_rates(net, path).rate_per_s.tolist() == [pytest.approx(0.01)]  # per minute -> per second


def test_haikou_rate_sources(data_dir):
    net = haikou_network(data_dir)
    month = month_rates(net, data_dir)
    assert len(month) == 39_510
    assert month.total_per_s * 60 == pytest.approx(51.83, abs=0.01)  # SOURCE.md: Σλ = 51.83 / min
    day = peak_order_rates(net, data_dir, "2017-05-01")
    assert day.total_per_s * 3600 == pytest.approx(2018)  # orders inside 08:00-09:00
    table = day_table_rates(net, data_dir)
    assert len(table) == 1698 and table.total_per_s * 3600 == pytest.approx(1766)
    with pytest.raises(DataNotFoundError, match="2017-06-30"):
        peak_order_rates(net, data_dir, "2017-06-30")
