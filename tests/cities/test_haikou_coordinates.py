"""A real city imported from a GraphML and a trip table with coordinates: Haikou's network written as an
OSMnx-style GraphML, and the raw 2017-05-01 08:00-09:00 DiDi orders with their real coordinates, each end
snapped to the nearest node."""

from __future__ import annotations

import networkx as nx
import pytest

from rpbench.cities.folder import read_city
from rpbench.cities.importer import Sources, import_city
from rpbench.cities.trips import TripOptions
from rpbench.data import read_peak_orders
from rpbench.scenarios import build_scenario
from rpbench.scenarios.common import haikou_network

pytestmark = pytest.mark.haikou
RAW = "demand_0800_0900/raw_orders_2017-05-01_0800-0900_by_departure_time.csv.gz"
PREFIX = "dwv_order_make_haikou_1."


def test_haikou_from_a_graphml_and_raw_coordinates(data_dir, tmp_path):
    net = haikou_network(data_dir)
    graph = nx.MultiDiGraph()
    for i in range(net.n_nodes):
        graph.add_node(int(net.node_id[i]), x=float(net.lon[i]), y=float(net.lat[i]))
    for a, b, length in zip(net.arc_tail, net.arc_head, net.arc_length_m, strict=True):
        graph.add_edge(int(net.node_id[a]), int(net.node_id[b]), length=float(length))
    nx.write_graphml(graph, tmp_path / "haikou.graphml")
    columns = {
        "time": f"{PREFIX}departure_time",
        "origin_lon": f"{PREFIX}starting_lng",
        "origin_lat": f"{PREFIX}starting_lat",
        "destination_lon": f"{PREFIX}dest_lng",
        "destination_lat": f"{PREFIX}dest_lat",
    }
    # the authors' network is coarse (a node every ~200 m): snap within 1 km
    city = import_city(
        "haikou",
        Sources(trips=data_dir / RAW, network=tmp_path / "haikou.graphml"),
        TripOptions(columns=columns, date="2017-05-01", snap_radius_m=1000.0),
        tmp_path / "haikou",
    )
    record = city.record
    assert record["network"]["nodes_kept"] == net.n_nodes and record["network"]["nodes_dropped"] == 0
    trips = record["trips"]
    assert trips["rows"] == 2035 and trips["date"] == "2017-05-01"
    dropped = trips["dropped"]
    assert dropped["an end farther than 1000 m from the network"] <= 0.01 * 2035
    assert trips["kept"] == 2035 - sum(dropped.values()) and trips["kept"] >= 0.95 * 2035
    assert trips["placed"]["snap_distance_m"]["median"] < 250
    mine = read_city(city.folder)
    hour = (mine.request_s >= 8 * 3600) & (mine.request_s < 9 * 3600)
    assert hour.sum() >= 0.95 * len(read_peak_orders(data_dir, "2017-05-01"))  # the authors' 2,018 of the hour
    # the city runs: its 08:00-09:00 hour at 30 %
    sc = build_scenario("city", city=str(city.folder), window="08:00-09:00", sample=0.3)
    assert abs(len(sc.orders) - 0.3 * hour.sum()) <= 1
