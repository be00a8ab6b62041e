"""A city's road network from a user's files: an OSMnx GraphML, or a node table and an arc table.

Both readers return :class:`RawRoads` (every node and arc as the file has them); :func:`reduce_roads` keeps
what rpbench can drive on: the largest strongly connected component (every order must be reachable from
every vehicle), one arc per ordered node pair (the shortest of parallel arcs) and no self-loops, and counts
what it dropped.

GraphML is read with networkx, the library OSMnx writes it with: node keys become the node ids when they
are all integers (OSMnx's OSM ids), else their positions in the file; ``x``/``y`` are longitude and
latitude (WGS84) and ``length`` the arc's length in metres, as OSMnx writes them.
"""

from __future__ import annotations

import gzip
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from rpbench.data._table import FLOAT, INT, read_table, require_file
from rpbench.data.road import MAX_LINK_M, NetworkTables
from rpbench.exceptions import DataError, one_line

#: What an error line about a user's network file tells them to do.
NETWORK_REMEDY = "check the file given to `rpbench city import` (--network, --nodes, --arcs)"
#: The columns of a node table and of an arc table (``--column NAME=SOURCE`` renames them).
NODE_COLUMNS = ("node_id", "lon", "lat")
ARC_COLUMNS = ("from_node", "to_node", "length_m")


@dataclass(frozen=True)
class RawRoads:
    """Nodes and directed arcs as a file holds them (``node_id`` in file order; arcs by node id)."""

    node_id: np.ndarray  # int64, unique
    lon: np.ndarray
    lat: np.ndarray
    arc_from: np.ndarray  # int64 node ids
    arc_to: np.ndarray
    arc_length_m: np.ndarray
    source: str  # the file names, for provenance (no folder)
    ids: str  # "file ids" or "positions": what node_id holds


@dataclass(frozen=True)
class Reduction:
    """What :func:`reduce_roads` kept and dropped."""

    tables: NetworkTables
    nodes_in: int
    arcs_in: int
    components: int
    nodes_dropped: int  # outside the largest strongly connected component
    arcs_dropped: int  # touching a dropped node
    self_loops: int
    parallel_merged: int  # arcs dropped because a shorter one joins the same ordered pair

    def record(self) -> dict[str, int]:
        return {
            "nodes_in": self.nodes_in,
            "arcs_in": self.arcs_in,
            "strong_components": self.components,
            "nodes_kept": len(self.tables.node_id),
            "nodes_dropped": self.nodes_dropped,
            "arcs_kept": len(self.tables.arc_from),
            "arcs_dropped_with_their_nodes": self.arcs_dropped,
            "self_loops_dropped": self.self_loops,
            "parallel_arcs_merged": self.parallel_merged,
        }


def read_graphml(path: Path) -> RawRoads:
    """An OSMnx GraphML (plain or ``.gz``): nodes with ``x`` and ``y``, arcs with ``length``."""
    import networkx as nx  # the importer's reader only: nothing else in rpbench needs it

    require_file(path, "network", NETWORK_REMEDY)
    try:
        with gzip.open(path, "rb") if path.suffix == ".gz" else open(path, "rb") as fh:
            graph = nx.read_graphml(fh, force_multigraph=True)
    except (OSError, EOFError, ValueError, KeyError, TypeError, ElementTree.ParseError, nx.NetworkXError) as exc:
        raise DataError(f"network file {str(path)!r} is not GraphML ({one_line(exc)}); {NETWORK_REMEDY}") from None
    keys = list(graph.nodes)
    if not keys:
        raise DataError(f"network file {str(path)!r} holds no nodes; {NETWORK_REMEDY}")
    ids, kind = _node_ids(keys)
    position = {key: i for i, key in enumerate(keys)}
    lon = _node_attribute(graph, keys, "x", path)
    lat = _node_attribute(graph, keys, "y", path)
    edges = list(graph.edges(data=True))
    tail = np.array([position[u] for u, _, _ in edges], dtype=np.int64)
    head = np.array([position[v] for _, v, _ in edges], dtype=np.int64)
    length = np.array([_number(d.get("length"), path, "arc", "length", i) for i, (_, _, d) in enumerate(edges)])
    raw = RawRoads(ids, lon, lat, ids[tail], ids[head], length, path.name, kind)
    _check(raw, path)
    return raw


def read_node_arc_tables(nodes: Path, arcs: Path, columns: Mapping[str, str] | None = None) -> RawRoads:
    """A node table (``node_id``, ``lon``, ``lat``) and an arc table (``from_node``, ``to_node``,
    ``length_m``), CSV plain or gzip; ``columns`` maps those names to the files' own."""
    names = {c: (columns or {}).get(c, c) for c in (*NODE_COLUMNS, *ARC_COLUMNS)}
    node_frame = read_table(
        nodes,
        "node table",
        {names["node_id"]: INT, names["lon"]: FLOAT, names["lat"]: FLOAT},
        rename={names[c]: c for c in NODE_COLUMNS},
        remedy=NETWORK_REMEDY,
    )
    arc_frame = read_table(
        arcs,
        "arc table",
        {names["from_node"]: INT, names["to_node"]: INT, names["length_m"]: FLOAT},
        rename={names[c]: c for c in ARC_COLUMNS},
        remedy=NETWORK_REMEDY,
    )
    if node_frame.empty:
        raise DataError(f"node table {str(nodes)!r} holds no nodes; {NETWORK_REMEDY}")
    raw = RawRoads(
        node_frame["node_id"].to_numpy(np.int64),
        node_frame["lon"].to_numpy(float),
        node_frame["lat"].to_numpy(float),
        arc_frame["from_node"].to_numpy(np.int64),
        arc_frame["to_node"].to_numpy(np.int64),
        arc_frame["length_m"].to_numpy(float),
        f"{nodes.name} + {arcs.name}",
        "file ids",
    )
    _check(raw, nodes)
    return raw


def reduce_roads(raw: RawRoads, name: str) -> Reduction:
    """The largest strongly connected component of ``raw``, self-loops dropped and parallel arcs merged
    (the shortest kept), as the tables a :class:`~rpbench.network.RoadNetwork` is built from."""
    n = len(raw.node_id)
    order = np.argsort(raw.node_id, kind="stable")
    sorted_ids = raw.node_id[order]
    tail = order[np.searchsorted(sorted_ids, raw.arc_from)]
    head = order[np.searchsorted(sorted_ids, raw.arc_to)]
    loop = tail == head
    tail, head, length = tail[~loop], head[~loop], raw.arc_length_m[~loop]
    graph = csr_matrix((np.ones(len(tail)), (tail, head)), shape=(n, n))
    components, label = connected_components(graph, directed=True, connection="strong")
    largest = int(np.argmax(np.bincount(label)))
    keep_node = label == largest
    keep_arc = keep_node[tail] & keep_node[head]
    tail, head, length = tail[keep_arc], head[keep_arc], length[keep_arc]
    key = tail * n + head
    srt = np.lexsort((length, key))
    first = np.ones(len(srt), dtype=bool)
    first[1:] = key[srt][1:] != key[srt][:-1]
    pick = srt[first]
    kept = np.flatnonzero(keep_node)
    tables = NetworkTables(
        name=name,
        node_id=raw.node_id[kept],
        lon=raw.lon[kept],
        lat=raw.lat[kept],
        arc_from=raw.node_id[tail[pick]],
        arc_to=raw.node_id[head[pick]],
        arc_length_m=length[pick],
        arc_link_id=np.arange(len(pick), dtype=np.int64),
        source=raw.source,
    )
    return Reduction(
        tables=tables,
        nodes_in=n,
        arcs_in=len(raw.arc_from),
        components=int(components),
        nodes_dropped=int(n - len(kept)),
        arcs_dropped=int((~keep_arc).sum()),
        self_loops=int(loop.sum()),
        parallel_merged=int(len(srt) - len(pick)),
    )


def _node_ids(keys: list[Any]) -> tuple[np.ndarray, str]:
    """Integer node keys as the ids (OSMnx's OSM ids), else the positions in the file."""
    try:
        ids = np.array([int(str(k)) for k in keys], dtype=np.int64)
    except (ValueError, OverflowError):
        return np.arange(len(keys), dtype=np.int64), "positions"
    if len(np.unique(ids)) != len(ids):  # "007" and "7": not usable as ids
        return np.arange(len(keys), dtype=np.int64), "positions"
    return ids, "file ids"


def _node_attribute(graph: Any, keys: list[Any], name: str, path: Path) -> np.ndarray:
    data = graph.nodes
    return np.array([_number(data[k].get(name), path, "node", name, i) for i, k in enumerate(keys)], dtype=float)


def _number(value: Any, path: Path, what: str, name: str, row: int) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not np.isfinite(number):
        shown = "missing" if value is None else f"{value!r}"
        raise DataError(
            f"network file {str(path)!r}: {what} {row + 1} has {name} {shown}, not a finite number "
            f"(an OSMnx GraphML gives every node x and y and every arc a length in metres); {NETWORK_REMEDY}"
        )
    return number


def _check(raw: RawRoads, path: Path) -> None:
    """Unique node ids, WGS84 coordinates, arcs between known nodes with lengths in (0, 1000 km]."""
    uniq, counts = np.unique(raw.node_id, return_counts=True)
    if (counts > 1).any():
        raise DataError(
            f"network file {str(path)!r}: node id {int(uniq[counts > 1][0])} appears twice; {NETWORK_REMEDY}"
        )
    bad = ~((np.abs(raw.lon) <= 180) & (np.abs(raw.lat) <= 90))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"network file {str(path)!r}: node {int(raw.node_id[i])} at ({raw.lon[i]:g}, {raw.lat[i]:g}) is not "
            f"in WGS84 degrees (longitude in [-180, 180], latitude in [-90, 90]); {NETWORK_REMEDY}"
        )
    known = np.isin(raw.arc_from, raw.node_id) & np.isin(raw.arc_to, raw.node_id)
    if not known.all():
        i = int(np.flatnonzero(~known)[0])
        node = raw.arc_from[i] if raw.arc_from[i] not in raw.node_id else raw.arc_to[i]
        raise DataError(f"network file {str(path)!r}: arc {i + 1} joins node {int(node)}, which it does not list")
    bad = ~((raw.arc_length_m > 0) & (raw.arc_length_m <= MAX_LINK_M))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"network file {str(path)!r}: arc {i + 1} has length {raw.arc_length_m[i]:g} m, not in (0, "
            f"{MAX_LINK_M:g}] m (lengths are in metres); {NETWORK_REMEDY}"
        )
    if not len(raw.arc_from):
        raise DataError(f"network file {str(path)!r} holds no arcs; {NETWORK_REMEDY}")
