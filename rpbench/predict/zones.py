"""Square zones of a road network, each represented by one of its nodes: how a sparse demand history is
pooled (docs/cities.md).

A day of a city's trips seen one hour at a time holds almost no origin-destination pair twice at the
level of nodes, so the rates of a history marked with a zone side (``History.zone_m``) are counted per pair
of zones, each zone standing for all its nodes through one representative node, and FL looks up an order's
prediction at its ends' representatives.
"""

from __future__ import annotations

import numpy as np

from rpbench.network import EARTH_RADIUS_M, RoadNetwork


def zone_representatives(network: RoadNetwork, zone_m: float) -> np.ndarray:
    """For every node, the node that represents its zone: squares of side ``zone_m`` on a local
    equirectangular projection, each represented by its node nearest the mean position of its nodes."""
    lat0 = np.radians(np.mean(network.lat))
    x = np.radians(network.lon) * EARTH_RADIUS_M * np.cos(lat0)
    y = np.radians(network.lat) * EARTH_RADIUS_M
    cell = np.floor((x - x.min()) / zone_m).astype(np.int64) * (1 << 31) + np.floor((y - y.min()) / zone_m).astype(
        np.int64
    )
    _, zone = np.unique(cell, return_inverse=True)
    count = np.bincount(zone)
    cx, cy = np.bincount(zone, weights=x) / count, np.bincount(zone, weights=y) / count
    gap = (x - cx[zone]) ** 2 + (y - cy[zone]) ** 2
    # per zone, the node of smallest gap: sort by (zone, gap) and take each zone's first
    order = np.lexsort((gap, zone))
    first = order[np.r_[True, zone[order][1:] != zone[order][:-1]]]
    representative = np.empty(len(count), dtype=np.int32)
    representative[zone[first]] = first
    return representative[zone]
