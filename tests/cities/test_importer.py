"""Importing a city: the component kept and what was dropped counted, trips placed by ids, positions or
coordinates, the folder written whole or not at all, and bad input one line."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from cities.conftest import grid_graph, node_trips
from rpbench.cities.folder import CITY_JSON, TRIPS, read_city
from rpbench.cities.importer import Sources, import_city
from rpbench.cities.trips import TripOptions
from rpbench.exceptions import DataError, ParameterError


def test_a_graphml_city_keeps_its_component_and_counts_what_it_dropped(graphml, node_table, tmp_path):
    city = import_city("grid", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "grid")
    net = city.record["network"]
    assert (net["nodes_in"], net["nodes_kept"], net["nodes_dropped"], net["strong_components"]) == (26, 25, 1, 2)
    assert net["self_loops_dropped"] == 1 and net["parallel_arcs_merged"] == 1 and net["arcs_kept"] == 80
    trips, going_nowhere = (
        city.record["trips"],
        int((node_trips()["origin_node"] == node_trips()["destination_node"]).sum()),
    )
    assert going_nowhere >= 3  # the three made so, and any the draw repeats
    assert trips["rows"] == 60 and trips["kept"] == 60 - going_nowhere
    assert trips["dropped"]["origin and destination are one node"] == going_nowhere
    assert any("1 of 26 nodes dropped" in line for line in city.notes)
    read = read_city(city.folder)
    assert read.network.n_nodes == 25 and len(read.request_s) == 60 - going_nowhere
    assert np.all(np.diff(read.request_s) >= 0)
    # the shorter of the two parallel arcs is the one kept
    arc = read.network.arc_index(*read.network.index_of([1000, 1001]))
    assert read.network.arc_length_m[arc] < 100


def test_node_tables_give_the_same_city_as_the_graphml(graphml, node_table, tmp_path):
    g = grid_graph()
    nodes = pd.DataFrame([(n, d["x"], d["y"]) for n, d in g.nodes(data=True)], columns=["id", "x", "y"])
    arcs = pd.DataFrame([(u, v, d["length"]) for u, v, d in g.edges(data=True)], columns=["u", "v", "length"])
    nodes.to_csv(tmp_path / "nodes.csv", index=False)
    arcs.to_csv(tmp_path / "arcs.csv.gz", index=False)
    columns = {"node_id": "id", "lon": "x", "lat": "y", "from_node": "u", "to_node": "v", "length_m": "length"}
    tables = import_city(
        "grid-tables",
        Sources(trips=node_table, nodes=tmp_path / "nodes.csv", arcs=tmp_path / "arcs.csv.gz", columns=columns),
        TripOptions(),
        tmp_path / "a",
    )
    graph = import_city("grid", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "b")
    assert tables.record["files"] == graph.record["files"]  # the same tables, byte for byte


def test_trips_by_position_in_the_network_file(graphml, tmp_path):
    order = list(grid_graph().nodes)
    trips = node_trips()
    trips["origin_node"] = [order.index(n) for n in trips["origin_node"]]
    trips["destination_node"] = [order.index(n) for n in trips["destination_node"]]
    trips["time"] = (trips["time"] // 60).astype(int)  # minutes
    trips.to_csv(tmp_path / "by-position.csv", index=False)
    node_trips().assign(time=trips["time"] * 60.0 + 0.5).to_csv(tmp_path / "ids.csv", index=False)
    city = import_city(
        "grid",
        Sources(trips=tmp_path / "by-position.csv", network=graphml),
        TripOptions(node_ids="positions", time_unit="min"),
        tmp_path / "grid",
    )
    by_id = import_city("ids", Sources(trips=tmp_path / "ids.csv", network=graphml), TripOptions(), tmp_path / "ids")
    assert city.record["trips"]["kept"] == by_id.record["trips"]["kept"]
    assert city.record["trips"]["time_resolution_s"] == 60.0 and by_id.record["trips"]["time_resolution_s"] == 1.0
    a, b = read_city(city.folder), read_city(by_id.folder)
    assert np.array_equal(a.origin, b.origin) and np.array_equal(a.destination, b.destination)


def test_coordinates_are_snapped_within_the_radius_and_iso_times_read(graphml, coordinate_table, tmp_path):
    city = import_city("grid", Sources(trips=coordinate_table, network=graphml), TripOptions(), tmp_path / "grid")
    trips = city.record["trips"]
    assert trips["date"] == "2016-06-01" and trips["dropped"]["an end farther than 500 m from the network"] == 2
    assert trips["placed"]["snap_distance_m"]["p95"] < 20
    assert trips["first_request_s"] >= 8 * 3600 and trips["last_request_s"] < 9 * 3600


def test_an_import_that_fails_while_writing_leaves_nothing(graphml, node_table, tmp_path, monkeypatch):
    """A failure while the tables are written (a full disk, say) leaves neither the folder nor its staging copy."""
    import rpbench.cities.folder as folder

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(folder, "file_sha256", full_disk)
    (tmp_path / "out").mkdir()
    with pytest.raises(OSError, match="No space left"):
        import_city("grid", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "out" / "grid")
    assert list((tmp_path / "out").iterdir()) == []


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda p: p.write_text("<graphml><node"), "is not GraphML"),
        (lambda p: p.write_text("not xml at all"), "is not GraphML"),
    ],
)
def test_a_network_that_is_not_graphml_is_one_line(make, message, node_table, tmp_path):
    bad = tmp_path / "bad.graphml"
    make(bad)
    with pytest.raises(DataError, match=message) as info:
        import_city("grid", Sources(trips=node_table, network=bad), TripOptions(), tmp_path / "grid")
    assert "\n" not in str(info.value) and not (tmp_path / "grid").exists()


def test_trip_tables_with_unknown_columns_no_trips_or_far_coordinates_are_one_line(graphml, tmp_path):
    cases = {
        "columns.csv": (pd.DataFrame({"when": [1.0], "from": [1000], "to": [1001]}), "needs time, origin_node"),
        "empty.csv": (node_trips().iloc[:0], "holds no trips"),
        "nowhere.csv": (node_trips().assign(destination_node=lambda f: f["origin_node"]), "no trip is left"),
        "unknown.csv": (node_trips().assign(origin_node=5), "name nodes the network file does not list"),
        "swapped.csv": (
            pd.DataFrame(
                {
                    "time": [0.0],
                    "origin_lon": [50.0],
                    "origin_lat": [10.0],
                    "destination_lon": [50.0],
                    "destination_lat": [10.001],
                }
            ),
            "longitude and latitude swapped",
        ),
        "late.csv": (node_trips().assign(time=90000.0), "not within the day"),
    }
    for name, (frame, message) in cases.items():
        frame.to_csv(tmp_path / name, index=False)
        with pytest.raises(DataError, match=message) as info:
            import_city("grid", Sources(trips=tmp_path / name, network=graphml), TripOptions(), tmp_path / "grid")
        assert "\n" not in str(info.value), name
        assert not (tmp_path / "grid").exists(), name


def test_bad_options_are_one_line(graphml, node_table, tmp_path):
    with pytest.raises(ParameterError, match="not a trip column"):
        TripOptions(columns={"origin": "x"})
    with pytest.raises(ParameterError, match="city name 'Big City'"):
        import_city("Big City", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "x")
    with pytest.raises(ParameterError, match="--network FILE .* or as --nodes FILE --arcs FILE"):
        Sources(trips=node_table)
    (tmp_path / "taken").mkdir()
    with pytest.raises(ParameterError, match="exists already"):
        import_city("grid", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "taken")


def test_a_damaged_city_folder_is_refused_by_name(graphml, node_table, tmp_path):
    city = import_city("grid", Sources(trips=node_table, network=graphml), TripOptions(), tmp_path / "grid")
    copy = tmp_path / "copy"
    shutil.copytree(city.folder, copy)
    trips = pd.read_csv(copy / TRIPS)
    trips.loc[0, "request_s"] += 1
    trips.to_csv(copy / TRIPS, index=False)
    with pytest.raises(DataError, match=r"trips.csv.gz is not the file the import wrote"):
        read_city(copy)
    record = json.loads((copy / CITY_JSON).read_text())
    record["format"] = "something else"
    (copy / CITY_JSON).write_text(json.dumps(record))
    with pytest.raises(DataError, match="is not a rpbench-city-1 description"):
        read_city(copy)
