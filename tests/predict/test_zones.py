"""Zones of a network: one representative node each, inside its zone; a history pooled over them keeps
its trips between zones and drops those inside one."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import line_network

from rpbench.network import EARTH_RADIUS_M
from rpbench.predict.hourly import history_zone_m, hourly_rates
from rpbench.predict.zones import zone_representatives
from rpbench.scenarios.base import Demand, History


def _positions_m(net):
    lat0 = np.radians(np.mean(net.lat))
    return np.radians(net.lon) * EARTH_RADIUS_M * np.cos(lat0), np.radians(net.lat) * EARTH_RADIUS_M


@pytest.mark.parametrize("zone_m", [1.0, 15.0, 45.0, 1e5])
def test_every_node_is_represented_by_a_node_of_its_own_zone(zone_m):
    net = line_network(12)
    rep = zone_representatives(net, zone_m)
    x, y = _positions_m(net)
    cell = np.floor((x - x.min()) / zone_m) * 1e9 + np.floor((y - y.min()) / zone_m)
    assert np.array_equal(cell[rep], cell)  # a representative lies in the zone it stands for
    assert np.array_equal(rep[rep], rep)  # and stands for itself
    assert len(np.unique(rep)) == len(np.unique(cell))  # one per zone
    if zone_m >= 1e5:
        assert len(np.unique(rep)) == 1


def test_a_pooled_history_counts_zone_pairs_and_drops_trips_inside_a_zone():
    net = line_network(12)
    rep = zone_representatives(net, 30.0)
    origin = np.array([0, 1, 0, 11], dtype=np.int32)
    destination = np.array([11, 10, 1, 0], dtype=np.int32)
    history = History(np.array([10.0, 20.0, 30.0, 40.0]), origin, destination, days=1, source="test", zone_m=30.0)
    demand = Demand(table="history", history=history)
    assert history_zone_m("auto", demand) == 30.0 and history_zone_m("auto", demand, 90.0) == 90.0
    assert history_zone_m("month", Demand(table="month", data_dir=".")) is None

    class View:
        network, name = net, "test"

    View.demand = demand
    (rates,) = hourly_rates(View(), "auto", 1)
    inside = rep[origin] == rep[destination]
    assert inside.sum() == 1  # 0 -> 1 stays in its zone
    assert rates.total_per_s * 3600 == pytest.approx(3)
    assert set(rates.origin.tolist()) <= set(rep.tolist()) and set(rates.destination.tolist()) <= set(rep.tolist())
