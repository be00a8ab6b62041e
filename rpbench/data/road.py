"""Readers for road networks: the authors' Haikou network and the predecessor one.

Both return :class:`NetworkTables`, plain arrays that
:class:`rpbench.network.RoadNetwork` turns into a directed graph.

* ``network/node.csv`` + ``network/link.csv.gz`` (osm2gmns format): one row per
  undirected road segment; rpbench adds the reverse arc of every link, as the
  authors' ``links.csv`` does.
* ``predecessor_trb2021_network/all_vertexes.csv.gz`` + ``all_edges.csv.gz``:
  already directed; an edge runs from ``head_ver`` to ``tail_ver`` (its
  polyline starts at ``head_ver``'s coordinates).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rpbench.data._table import FLOAT, INT, TEXT, read_table
from rpbench.exceptions import DataError

NODE_FILE = Path("network") / "node.csv"
LINK_FILE = Path("network") / "link.csv.gz"
PRED_VERTEX_FILE = Path("predecessor_trb2021_network") / "all_vertexes.csv.gz"
PRED_EDGE_FILE = Path("predecessor_trb2021_network") / "all_edges.csv.gz"
#: Longest road link accepted (1,000 km: longer is a unit error, and sums of absurd lengths overflow).
MAX_LINK_M = 1e6


@dataclass(frozen=True)
class NetworkTables:
    """Nodes and directed arcs as read from disk (ids as in the files)."""

    name: str
    node_id: np.ndarray  # int64, unique
    lon: np.ndarray  # float64, WGS84 degrees
    lat: np.ndarray  # float64
    arc_from: np.ndarray  # int64 node ids
    arc_to: np.ndarray  # int64 node ids
    arc_length_m: np.ndarray  # float64, > 0
    arc_link_id: np.ndarray  # int64, the file's link id (shared by both directions)
    source: str  # file paths, for provenance


def read_haikou_network(data_dir: Path) -> NetworkTables:
    """The authors' Haikou network: 3,901 nodes, 5,458 two-way links."""
    node_path, link_path = data_dir / NODE_FILE, data_dir / LINK_FILE
    nodes = read_table(node_path, "network node", {"node_id": INT, "x_coord": FLOAT, "y_coord": FLOAT})
    links = read_table(
        link_path, "network link", {"link_id": INT, "from_node_id": INT, "to_node_id": INT, "length": FLOAT}
    )
    _check_nodes(nodes["node_id"].to_numpy(), node_path)
    _check_coordinates(nodes["x_coord"].to_numpy(), nodes["y_coord"].to_numpy(), node_path)
    a = links["from_node_id"].to_numpy()
    b = links["to_node_id"].to_numpy()
    length = links["length"].to_numpy()
    link_id = links["link_id"].to_numpy()
    _check_arcs(nodes["node_id"].to_numpy(), a, b, length, link_path)
    return NetworkTables(
        name="haikou",
        node_id=nodes["node_id"].to_numpy(),
        lon=nodes["x_coord"].to_numpy(),
        lat=nodes["y_coord"].to_numpy(),
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.concatenate([length, length]),
        arc_link_id=np.concatenate([link_id, link_id]),
        source=f"{node_path} + {link_path}",
    )


def read_predecessor_network(data_dir: Path) -> NetworkTables:
    """The TR-B 2021 Haikou network: 724 vertices, 1,955 directed edges."""
    vpath, epath = data_dir / PRED_VERTEX_FILE, data_dir / PRED_EDGE_FILE
    vertices = read_table(vpath, "predecessor vertex", {"id": INT, "coor": TEXT})
    edges = read_table(epath, "predecessor edge", {"id": INT, "length": FLOAT, "head_ver": INT, "tail_ver": INT})
    lonlat = np.array([_parse_pair(s, vpath, i) for i, s in enumerate(vertices["coor"])], dtype=float)
    ids = vertices["id"].to_numpy()
    _check_nodes(ids, vpath)
    _check_coordinates(lonlat[:, 0], lonlat[:, 1], vpath)
    a = edges["head_ver"].to_numpy()
    b = edges["tail_ver"].to_numpy()
    length = edges["length"].to_numpy()
    _check_arcs(ids, a, b, length, epath)
    return NetworkTables(
        name="haikou-trb2021",
        node_id=ids,
        lon=lonlat[:, 0],
        lat=lonlat[:, 1],
        arc_from=a,
        arc_to=b,
        arc_length_m=length,
        arc_link_id=edges["id"].to_numpy(),
        source=f"{vpath} + {epath}",
    )


def _parse_pair(text: str, path: Path, row: int) -> tuple[float, float]:
    try:
        value = ast.literal_eval(str(text))
        lon, lat = float(value[0]), float(value[1])
    except (ValueError, SyntaxError, TypeError, IndexError):
        raise DataError(
            f"predecessor vertex file {str(path)!r}, column 'coor', data row {row + 1}: "
            f"value {text!r} is not a '[lon, lat]' pair"
        ) from None
    return lon, lat


def _check_nodes(node_id: np.ndarray, path: Path) -> None:
    if len(node_id) == 0:
        raise DataError(f"network file {str(path)!r} holds no nodes")
    uniq, counts = np.unique(node_id, return_counts=True)
    if (counts > 1).any():
        raise DataError(f"network file {str(path)!r}: node id {int(uniq[counts > 1][0])} appears more than once")


def _check_arcs(node_id: np.ndarray, a: np.ndarray, b: np.ndarray, length: np.ndarray, path: Path) -> None:
    known = np.isin(a, node_id) & np.isin(b, node_id)
    if not known.all():
        row = int(np.flatnonzero(~known)[0])
        bad = a[row] if a[row] not in node_id else b[row]
        raise DataError(f"network file {str(path)!r}, data row {row + 1}: node id {int(bad)} is not in the node file")
    if (length <= 0).any():
        row = int(np.flatnonzero(length <= 0)[0])
        raise DataError(f"network file {str(path)!r}, data row {row + 1}: length {length[row]} m is not positive")
    # A link of 1e300 m is finite, but path sums over such links overflow to inf (= "unreachable").
    if (length > MAX_LINK_M).any():
        row = int(np.flatnonzero(length > MAX_LINK_M)[0])
        raise DataError(
            f"network file {str(path)!r}, data row {row + 1}: length {length[row]:g} m "
            f"exceeds {MAX_LINK_M:g} m; lengths are in metres"
        )


def _check_coordinates(lon: np.ndarray, lat: np.ndarray, path: Path) -> None:
    """WGS84 degrees: anything else would snap orders to nonsense nodes."""
    bad = ~((np.abs(lon) <= 180) & (np.abs(lat) <= 90))
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"network file {str(path)!r}, data row {row + 1}: coordinates ({lon[row]:g}, {lat[row]:g}) "
            "are not WGS84 degrees (longitude in [-180, 180], latitude in [-90, 90])"
        )
