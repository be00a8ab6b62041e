"""The state space of the value: square grid cells of the road network and time bins.

A node's cell comes from its position projected onto a local plane (metres east and north of the
network's south-west corner, equirectangular at the network's mean latitude: a few metres of error
over a city, far below a cell), so cells are the same for every scenario on one network.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rpbench.network import RoadNetwork

EARTH_M_PER_DEG_LAT = 111_320.0


@dataclass(frozen=True, eq=False)
class Grid:
    """Cells of ``cell_m`` metres and time bins of ``bin_s`` seconds over ``n_bins`` bins.

    ``node_cell[i]`` is node i's cell (0 .. ``n_cells`` - 1, row-major from the south-west corner).
    A time at or beyond the last bin's start falls in the last bin.
    """

    cell_m: float
    bin_s: float
    n_bins: int
    node_cell: np.ndarray
    n_cells: int

    @classmethod
    def of(cls, network: RoadNetwork, cell_m: float, bin_s: float, horizon_s: float) -> Grid:
        lat0 = float(np.mean(network.lat)) if network.n_nodes else 0.0
        x = (network.lon - network.lon.min()) * EARTH_M_PER_DEG_LAT * np.cos(np.radians(lat0))
        y = (network.lat - network.lat.min()) * EARTH_M_PER_DEG_LAT
        ix = np.floor(x / cell_m).astype(np.int64)
        iy = np.floor(y / cell_m).astype(np.int64)
        nx = int(ix.max()) + 1 if network.n_nodes else 1
        ny = int(iy.max()) + 1 if network.n_nodes else 1
        n_bins = max(1, int(np.ceil(horizon_s / bin_s - 1e-9)))
        return cls(float(cell_m), float(bin_s), n_bins, iy * nx + ix, nx * ny)

    @property
    def n_states(self) -> int:
        return self.n_cells * self.n_bins

    def time_bin(self, t_s: np.ndarray | float) -> np.ndarray:
        return np.clip(np.floor(np.asarray(t_s, dtype=np.float64) / self.bin_s), 0, self.n_bins - 1).astype(np.int64)

    def state(self, node: np.ndarray, t_s: np.ndarray | float) -> np.ndarray:
        """The state index ``cell * n_bins + bin`` of a vehicle at ``node`` at time ``t_s``."""
        return self.node_cell[np.asarray(node, dtype=np.int64)] * self.n_bins + self.time_bin(t_s)
