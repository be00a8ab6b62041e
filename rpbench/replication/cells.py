"""The authors' 0.05 degree grid cells (their ``Network.loadZones`` / ``generateIndex``), rebuilt.

Cells are laid from the network's minimum longitude and latitude in steps of
0.05 degrees; a node belongs to a cell when it lies *strictly* inside it, so a
node on a cell edge (the node holding the minimum coordinate, for one) has no
cell and, in the authors' matching, no candidate vehicle.  The minimum and
maximum are found with their ``if larger: ... elif smaller:`` scan, which
skips the minimum test whenever the maximum was just raised; that is kept,
since it can shift the grid.
"""

from __future__ import annotations

import numpy as np

CELL_DEG = 0.05
NO_CELL = -1


def _authors_bounds(lon: np.ndarray, lat: np.ndarray) -> tuple[float, float, float, float]:
    min_x = min_y = 8888.0
    max_x = max_y = 0.0
    for x, y in zip(lon.tolist(), lat.tolist(), strict=True):
        if y > max_y:
            max_y = y
        elif y < min_y:
            min_y = y
        if x > max_x:
            max_x = x
        elif x < min_x:
            min_x = x
    return min_x, min_y, max_x, max_y


def node_cells(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    """Cell id per node in node order (``NO_CELL`` for a node on an edge)."""
    lon = np.asarray(lon, dtype=np.float64)
    lat = np.asarray(lat, dtype=np.float64)
    min_x, min_y, max_x, max_y = _authors_bounds(lon, lat)
    xs = np.arange(min_x, max_x, CELL_DEG)
    ys = np.arange(min_y, max_y, CELL_DEG)
    cell = np.full(len(lon), NO_CELL, dtype=np.int64)
    # Cell ids as the authors number them: x outer, y inner.
    for ix, x in enumerate(xs):
        in_x = (lon > x) & (lon < x + CELL_DEG)
        if not in_x.any():
            continue
        for iy, y in enumerate(ys):
            inside = in_x & (lat > y) & (lat < y + CELL_DEG)
            cell[inside] = ix * len(ys) + iy
    return cell
