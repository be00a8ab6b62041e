"""Small generated cities: a GraphML as OSMnx writes one and trip tables of node ids and of coordinates."""

from __future__ import annotations

from pathlib import Path

import networkx as nx
import numpy as np
import pandas as pd
import pytest

from rpbench.network import great_circle_m

#: The grid's south-west corner and spacing (about 110 m by 70 m at this latitude).
LON0, LAT0, STEP = 10.0, 50.0, 0.001
SIDE = 5


def grid_graph() -> nx.MultiDiGraph:
    """A 5 x 5 two-way grid with OSM-like integer node ids, plus what an import must drop: a node reachable
    only one way (outside the strongly connected component), a parallel arc and a self-loop."""
    g = nx.MultiDiGraph()
    node = {(i, j): 1000 + i * SIDE + j for i in range(SIDE) for j in range(SIDE)}
    for (i, j), n in node.items():
        g.add_node(n, x=LON0 + STEP * j, y=LAT0 + STEP * i, osmid=n)
    for (i, j), n in node.items():
        for di, dj in ((0, 1), (1, 0)):
            if (i + di, j + dj) in node:
                m = node[(i + di, j + dj)]
                length = float(
                    great_circle_m(LON0 + STEP * j, LAT0 + STEP * i, LON0 + STEP * (j + dj), LAT0 + STEP * (i + di))
                )
                g.add_edge(n, m, length=length)
                g.add_edge(m, n, length=length)
    g.add_node(9999, x=LON0 - STEP, y=LAT0, osmid=9999)  # a one-way spur: out of the component
    g.add_edge(9999, 1000, length=70.0)
    g.add_edge(1000, 1001, length=500.0)  # parallel to the grid's 1000 -> 1001, longer: merged away
    g.add_edge(1002, 1002, length=5.0)  # a self-loop
    return g


@pytest.fixture
def graphml(tmp_path) -> Path:
    path = tmp_path / "grid.graphml"
    nx.write_graphml(grid_graph(), path)
    return path


def node_trips(n: int = 60, seed: int = 0) -> pd.DataFrame:
    """Trips between grid nodes (ids), over the morning, a few of them going nowhere."""
    rng = np.random.default_rng(seed)
    ids = np.array([1000 + k for k in range(SIDE * SIDE)])
    origin, destination = rng.choice(ids, n), rng.choice(ids, n)
    destination[:3] = origin[:3]  # three trips going nowhere
    return pd.DataFrame(
        {
            "time": np.sort(rng.uniform(7 * 3600, 10 * 3600, n)).round(1),
            "origin_node": origin,
            "destination_node": destination,
        }
    )


@pytest.fixture
def node_table(tmp_path) -> Path:
    path = tmp_path / "trips.csv"
    node_trips().to_csv(path, index=False)
    return path


def coordinate_trips(n: int = 60, seed: int = 1) -> pd.DataFrame:
    """Trips by coordinates within a few metres of the grid's nodes, and two from far away."""
    rng = np.random.default_rng(seed)
    i, j = rng.integers(0, SIDE, (2, n)), rng.integers(0, SIDE, (2, n))
    jitter = rng.normal(0, 0.00005, (4, n))
    frame = pd.DataFrame(
        {
            "time": [f"2016-06-01 08:{m // 60:02d}:{m % 60:02d}" for m in np.sort(rng.integers(0, 3600, n))],
            "origin_lon": LON0 + STEP * j[0] + jitter[0],
            "origin_lat": LAT0 + STEP * i[0] + jitter[1],
            "destination_lon": LON0 + STEP * j[1] + jitter[2],
            "destination_lat": LAT0 + STEP * i[1] + jitter[3],
        }
    )
    frame.loc[:1, "origin_lon"] = LON0 + 1.0  # about 70 km east: off the network
    return frame


@pytest.fixture
def coordinate_table(tmp_path) -> Path:
    path = tmp_path / "trips-coordinates.csv"
    coordinate_trips().to_csv(path, index=False)
    return path
