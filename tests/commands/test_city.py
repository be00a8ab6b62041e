"""``rpbench city import`` and ``rpbench city list``: a city imported into the data home runs by name; bad
input is one line, exit status 2, and nothing is written."""

from __future__ import annotations

import json

import networkx as nx
import pytest
from cities.conftest import grid_graph, node_trips

from rpbench.cli import main


@pytest.fixture
def home(tmp_path, monkeypatch):
    """An empty data home (cities are imported into it)."""
    monkeypatch.setenv("RPBENCH_DATA_HOME", str(tmp_path / "home"))
    return tmp_path / "home"


@pytest.fixture
def files(tmp_path):
    nx.write_graphml(grid_graph(), tmp_path / "grid.graphml")
    node_trips(200).assign(time=lambda f: f["time"] - 7 * 3600 + 8 * 3600 - 3600).to_csv(
        tmp_path / "trips.csv", index=False
    )
    return tmp_path / "grid.graphml", tmp_path / "trips.csv"


def test_import_list_and_run_a_city_by_name(home, files, capsys, tmp_path):
    graph, trips = files
    assert main(["city", "import", "grid", "--network", str(graph), "--trips", str(trips), "--json"]) == 0
    out, err = capsys.readouterr()
    record = json.loads(out)
    assert record["folder"] == str(home / "cities" / "grid") and record["network"]["nodes_kept"] == 25
    assert "rpbench: note: 1 of 26 nodes dropped" in err
    assert main(["city", "list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["imported"] == ["grid"] and "manhattan" in listed["builtin"]
    code = main(
        ["run", "--scenario", "city", "--city", "grid", "--window", "08:00-09:00", "--strategies", "mb,bound",
         "--out", str(tmp_path / "run"), "--no-progress"]
    )  # fmt: skip
    assert code == 0, capsys.readouterr().err
    meta = json.loads((tmp_path / "run" / "meta.json").read_text())
    assert meta["scenario"]["args"]["city"] == "grid" and meta["scenario"]["name"] == "city"
    assert main(["check", str(tmp_path / "run")]) == 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--trips", "{trips}"], "give the network as --network FILE (GraphML) or as --nodes FILE --arcs FILE"),
        (["--network", "{trips}", "--trips", "{trips}"], "is not GraphML"),
        (["--network", "{graph}", "--trips", "{trips}", "--column", "origin=o"], "--column 'origin=o'"),
        (["--network", "{graph}", "--trips", "{trips}", "--column", "time=when"], "it needs when, origin_node"),
        (["--network", "{graph}", "--trips", "{graph}"], "trip table"),
        (["--network", "{graph}", "--trips", "{trips}", "--node-ids", "positions"], "not a position"),
        (["--network", "{graph}", "--trips", "{trips}", "--snap-radius", "-3"], "--snap-radius"),
        (["--network", "{graph}", "--trips", "{trips}", "--speed", "900"], "--speed 900.0 km/h"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(home, files, capsys, args, message):
    graph, trips = files
    argv = ["city", "import", "grid", *(a.format(graph=graph, trips=trips) for a in args)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("rpbench: error:") and message in err, err
    assert not home.exists()


def test_a_name_already_imported_is_refused(home, files, capsys):
    graph, trips = files
    assert main(["city", "import", "grid", "--network", str(graph), "--trips", str(trips)]) == 0
    capsys.readouterr()
    assert main(["city", "import", "grid", "--network", str(graph), "--trips", str(trips)]) == 2
    assert "exists already" in capsys.readouterr().err
