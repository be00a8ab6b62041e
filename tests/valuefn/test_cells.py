"""The value's state space: nodes at known positions fall in the expected cells, time bins clamp."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.data.road import NetworkTables
from rpbench.network import RoadNetwork
from rpbench.scenarios.registry import build_scenario
from rpbench.valuefn.cells import EARTH_M_PER_DEG_LAT, Grid

LON0, LAT0 = 110.0, 20.0


def network_at(east_north_m: list[tuple[float, float]]) -> RoadNetwork:
    """A path network through nodes placed ``(east, north)`` metres from (LON0, LAT0).

    Positions are converted at LAT0's scale; the grid projects at the nodes' mean latitude, a few
    millimetres per kilometre away, so every node is placed at least 100 m from a cell edge.
    """
    east = np.array([p[0] for p in east_north_m])
    north = np.array([p[1] for p in east_north_m])
    n = len(east_north_m)
    ids = np.arange(n)
    a, b = ids[:-1], ids[1:]
    length = np.full(n - 1, 500.0)
    tables = NetworkTables(
        name="placed",
        node_id=ids,
        lon=LON0 + east / (EARTH_M_PER_DEG_LAT * np.cos(np.radians(LAT0))),
        lat=LAT0 + north / EARTH_M_PER_DEG_LAT,
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.concatenate([length, length]),
        arc_link_id=np.concatenate([np.arange(n - 1)] * 2),
        source="tests",
    )
    return RoadNetwork.from_tables(tables)


def test_nodes_at_known_positions_fall_in_the_expected_cells():
    """Cells are row-major from the south-west corner: (ix, iy) -> iy * nx + ix, nx = 3, ny = 2 here."""
    net = network_at([(0.0, 0.0), (2500.0, 0.0), (300.0, 1200.0), (1500.0, 1500.0), (2900.0, 1900.0), (899.0, 0.0)])
    grid = Grid.of(net, cell_m=1000.0, bin_s=600.0, horizon_s=3600.0)
    assert grid.n_cells == 3 * 2
    assert grid.node_cell.tolist() == [0, 2, 3, 4, 5, 0]
    # a coarser grid: everything within 2 km east and north is cell 0; the 2.5 km and 2.9 km nodes are column 1
    coarse = Grid.of(net, cell_m=2000.0, bin_s=600.0, horizon_s=3600.0)
    assert (coarse.n_cells, coarse.node_cell.tolist()) == (2, [0, 1, 0, 0, 1, 0])


def test_the_grid_does_not_depend_on_the_corner_node_alone():
    """Moving the whole network keeps its cells: they are measured from its own south-west corner."""
    spots = [(0.0, 0.0), (2500.0, 0.0), (300.0, 1200.0), (1500.0, 1500.0)]
    here = Grid.of(network_at(spots), 1000.0, 600.0, 3600.0)
    moved = Grid.of(network_at([(e + 40_000.0, n + 30_000.0) for e, n in spots]), 1000.0, 600.0, 3600.0)
    assert moved.node_cell.tolist() == here.node_cell.tolist() == [0, 2, 3, 4]


def test_time_bins_and_their_count():
    """Bins of bin_s seconds cover the horizon (a partial last bin counts); times before 0 read bin 0 and
    times at or past the last bin's start read the last bin."""
    net = network_at([(0.0, 0.0), (2500.0, 0.0)])
    assert Grid.of(net, 1000.0, 600.0, 3600.0).n_bins == 6
    assert Grid.of(net, 1000.0, 600.0, 3601.0).n_bins == 7
    assert Grid.of(net, 1000.0, 600.0, 100.0).n_bins == 1
    grid = Grid.of(net, 1000.0, 600.0, 3600.0)
    t = np.array([-5.0, 0.0, 599.9, 600.0, 3000.0, 3599.0, 3600.0, 1e6])
    assert grid.time_bin(t).tolist() == [0, 0, 0, 1, 5, 5, 5, 5]
    assert int(grid.time_bin(1234.0)) == 2
    # state = cell * n_bins + bin: node 1 is cell 2
    assert grid.state(np.array([0, 1, 1]), np.array([0.0, 700.0, 9e9])).tolist() == [0, 2 * 6 + 1, 2 * 6 + 5]
    assert grid.n_states == 3 * 6  # one row of three cells


def test_a_grid_made_by_hand():
    """A Grid can be given its cells directly (the learning tests' three-cell example)."""
    grid = Grid(cell_m=1.0, bin_s=100.0, n_bins=2, node_cell=np.array([0, 1, 2]), n_cells=3)
    assert grid.n_states == 6
    assert grid.state(np.array([2, 0]), np.array([150.0, 50.0])).tolist() == [5, 0]


def test_the_toy_city_is_cut_into_equal_cells():
    """The toy city's 12 x 12 grid of streets: 6 x 6 cells of 1 km, four nodes in each."""
    net = build_scenario("toy", sample=0.1).network
    grid = Grid.of(net, 1000.0, 600.0, 3600.0)
    assert grid.n_cells == 36
    assert np.bincount(grid.node_cell, minlength=grid.n_cells).tolist() == [4] * 36
    with pytest.raises(IndexError):
        grid.state(np.array([net.n_nodes]), 0.0)
