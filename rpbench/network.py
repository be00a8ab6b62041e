"""Directed road network, all-pairs shortest distances and paths, node snapping.

:class:`RoadNetwork` is an immutable directed graph over internal node indices
``0..n-1`` (``node_id[i]`` is the id used in the data files).  Its
:meth:`RoadNetwork.distances` is the *one* distance oracle every part of
rpbench uses (docs/algorithms.md §1: "the same distance oracle the simulator
uses"): all-pairs shortest distances and a predecessor matrix from Dijkstra
(``scipy.sparse.csgraph``), cached on disk in the user cache directory under
a hash of the network content, with a SHA-256 digest that every load checks
(:meth:`Distances.load_or_build`).  Shortest paths are read off the predecessor
matrix, so the path a prediction assumes is the path the simulator drives.
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import scipy
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, shortest_path
from scipy.spatial import cKDTree

from rpbench.data.road import NetworkTables
from rpbench.exceptions import DataError, ParameterError, one_line
from rpbench.files.paths import builder_lock, cache_dir, cache_write_error, temporary_file

EARTH_RADIUS_M = 6_371_008.8
_NO_PRED = -9999  # scipy's marker for "no predecessor"


def great_circle_m(lon1, lat1, lon2, lat2) -> np.ndarray:
    """Haversine distance in metres between WGS84 points (vectorised)."""
    lon1, lat1, lon2, lat2 = (np.radians(np.asarray(x, dtype=float)) for x in (lon1, lat1, lon2, lat2))
    a = np.sin((lat2 - lat1) / 2) ** 2 + np.cos(lat1) * np.cos(lat2) * np.sin((lon2 - lon1) / 2) ** 2
    return 2 * EARTH_RADIUS_M * np.arcsin(np.sqrt(np.clip(a, 0.0, 1.0)))


@dataclass(frozen=True, eq=False)
class RoadNetwork:
    """A strongly connected directed road graph with lengths in metres.

    Parallel arcs between the same pair of nodes are merged (the shortest
    wins) and self-loops dropped, so an arc is identified by its (tail, head).
    """

    name: str
    node_id: np.ndarray  # int64 file ids; position = internal index
    lon: np.ndarray
    lat: np.ndarray
    arc_tail: np.ndarray  # int32 internal indices
    arc_head: np.ndarray
    arc_length_m: np.ndarray  # float64
    arc_link_id: np.ndarray  # int64 file link ids
    source: str = ""
    _index: dict = field(default_factory=dict, repr=False, compare=False)

    # ----------------------------------------------------------------- build
    @classmethod
    def from_tables(cls, tables: NetworkTables) -> RoadNetwork:
        """Build from reader output, checking ids and strong connectivity."""
        order = np.argsort(tables.node_id, kind="stable")
        node_id = tables.node_id[order].astype(np.int64)
        tail = np.searchsorted(node_id, tables.arc_from)
        head = np.searchsorted(node_id, tables.arc_to)
        keep = tail != head
        tail, head = tail[keep], head[keep]
        length = tables.arc_length_m[keep].astype(np.float64)
        link = tables.arc_link_id[keep].astype(np.int64)
        # Merge parallel arcs, keeping the shortest (csgraph would sum duplicates).
        key = tail.astype(np.int64) * len(node_id) + head
        srt = np.lexsort((length, key))
        first = np.ones(len(srt), dtype=bool)
        first[1:] = key[srt][1:] != key[srt][:-1]
        pick = srt[first]
        net = cls(
            name=tables.name,
            node_id=node_id,
            lon=tables.lon[order].astype(float),
            lat=tables.lat[order].astype(float),
            arc_tail=tail[pick].astype(np.int32),
            arc_head=head[pick].astype(np.int32),
            arc_length_m=length[pick],
            arc_link_id=link[pick],
            source=tables.source,
        )
        net.check_strongly_connected()
        return net

    def check_strongly_connected(self) -> None:
        n_comp, labels = connected_components(self.csr, directed=True, connection="strong")
        if n_comp != 1:
            largest = int(np.bincount(labels).max())
            raise DataError(
                f"road network {self.name!r} ({self.source}) is not strongly connected: "
                f"{n_comp} strong components, the largest holds {largest} of {self.n_nodes} nodes; "
                "every node must be reachable from every other"
            )

    # ------------------------------------------------------------ structure
    @property
    def n_nodes(self) -> int:
        return len(self.node_id)

    @property
    def n_arcs(self) -> int:
        return len(self.arc_tail)

    @cached_property
    def csr(self) -> csr_matrix:
        return csr_matrix((self.arc_length_m, (self.arc_tail, self.arc_head)), shape=(self.n_nodes,) * 2)

    @cached_property
    def _arc_keys(self) -> tuple[np.ndarray, np.ndarray]:
        key = self.arc_tail.astype(np.int64) * self.n_nodes + self.arc_head
        order = np.argsort(key)
        return key[order], order

    def arc_index(self, tail, head) -> np.ndarray:
        """Arc indices of (tail, head) node pairs; -1 where no such arc exists."""
        keys, order = self._arc_keys
        q = np.asarray(tail, dtype=np.int64) * self.n_nodes + np.asarray(head, dtype=np.int64)
        # searchsorted never returns < 0, and np.minimum costs a fraction of np.clip on the simulator's short
        # paths (called for every plan a vehicle gets)
        pos = np.minimum(keys.searchsorted(q), len(keys) - 1)
        return np.where(keys[pos] == q, order[pos], -1)

    @cached_property
    def out_offsets(self) -> np.ndarray:
        """CSR offsets of outgoing arcs (``out_arcs[out_offsets[u]:out_offsets[u+1]]``)."""
        counts = np.bincount(self.arc_tail, minlength=self.n_nodes)
        return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    @cached_property
    def out_arcs(self) -> np.ndarray:
        return np.argsort(self.arc_tail, kind="stable").astype(np.int32)

    def index_of(self, ids, *, what: str = "node id") -> np.ndarray:
        """Internal indices of file node ids, with a clear error on an unknown id."""
        ids = np.asarray(ids, dtype=np.int64)
        pos = np.clip(np.searchsorted(self.node_id, ids), 0, self.n_nodes - 1)
        bad = self.node_id[pos] != ids
        if bad.any():
            first = int(ids[np.flatnonzero(bad)[0]])
            raise DataError(
                f"{what} {first} is not a node of the {self.name!r} network ({int(bad.sum())} unknown id(s) in all)"
            )
        return pos.astype(np.int32)

    @cached_property
    def content_hash(self) -> str:
        """Hash of everything that determines shortest paths (plus scipy's version)."""
        h = hashlib.sha256()
        h.update(f"{self.n_nodes}|{scipy.__version__}|".encode())
        for arr in (self.arc_tail, self.arc_head, self.arc_length_m):
            h.update(np.ascontiguousarray(arr).tobytes())
        return h.hexdigest()[:20]

    # ------------------------------------------------------------ distances
    def distances(self, *, use_cache: bool = True) -> Distances:
        """The all-pairs distance oracle (built once per network object)."""
        oracle = self._index.get("oracle")
        if oracle is None:
            oracle = Distances.load_or_build(self, use_cache=use_cache)
            self._index["oracle"] = oracle
        return oracle


@dataclass(frozen=True, eq=False)
class Distances:
    """All-pairs shortest distances ``dist[o, d]`` (m) and predecessors ``pred[o, d]``."""

    network: RoadNetwork
    dist: np.ndarray  # float64 (n, n)
    pred: np.ndarray  # int32 (n, n); pred[o, o] = -1
    build_s: float = 0.0
    from_cache: bool = False

    @classmethod
    def build(cls, network: RoadNetwork) -> Distances:
        t0 = time.perf_counter()
        dist, pred = shortest_path(network.csr, method="D", directed=True, return_predecessors=True)
        pred = pred.astype(np.int32)
        pred[pred == _NO_PRED] = -1
        return cls(network, dist, pred, build_s=time.perf_counter() - t0)

    @classmethod
    def load_or_build(cls, network: RoadNetwork, *, use_cache: bool = True) -> Distances:
        """The oracle from the disk cache when its content checks out, else built and cached.

        The cache holds ``apsp-<hash>-dist.npy``, ``-pred.npy`` and
        ``.sha256`` (the SHA-256 of both arrays, written after them).  A
        table whose values changed on disk keeps its shape, so only a content
        check catches it: every load re-hashes the arrays (a fraction of a
        second for Haikou's 180 MB, against seconds to rebuild).  A mismatch,
        a missing digest or an unreadable file is rebuilt, with one note on
        stderr; a cache folder that cannot be written is a :class:`CacheError`.
        """
        if not use_cache:
            return cls.build(network)
        files = _ApspFiles.of(network)
        t0 = time.perf_counter()
        arrays, _ = files.load_verified(network.n_nodes)
        if arrays is not None:
            return cls(network, *arrays, build_s=time.perf_counter() - t0, from_cache=True)
        # Another process (a parallel sweep's worker, the comparison's second process) may be writing the
        # files right now: a table without its digest yet is theirs to finish, not a fault, so the files are
        # judged once their lock is ours.  The wait is silent: it is shorter than building the table.
        with builder_lock(files.lock):
            arrays, problem = files.load_verified(network.n_nodes)
            if arrays is not None:
                return cls(network, *arrays, build_s=time.perf_counter() - t0, from_cache=True)
            if problem:
                print(
                    f"rpbench: note: the cached all-pairs distances {files.stem.name}-* {problem}; rebuilding them",
                    file=sys.stderr,
                )
            oracle = cls.build(network)
            files.save(oracle.dist, oracle.pred)
        return oracle

    # -------------------------------------------------------------- queries
    def __call__(self, origin, destination) -> np.ndarray:
        """Vectorised shortest distance l(o, d) in metres."""
        return self.dist[origin, destination]

    def path_nodes(self, origin: int, destination: int) -> np.ndarray:
        """Node sequence of the shortest path o -> d (``[o]`` when o == d)."""
        nodes = [int(destination)]
        row = self.pred[int(origin)]
        cur = int(destination)
        while cur != origin:
            cur = int(row[cur])
            if cur < 0:
                raise ParameterError(f"no path from node {origin} to node {destination}")
            nodes.append(cur)
        return np.asarray(nodes[::-1], dtype=np.int32)

    def path_arcs(self, origin: int, destination: int) -> np.ndarray:
        """Arc indices of the shortest path o -> d (empty when o == d)."""
        nodes = self.path_nodes(origin, destination)
        return self.network.arc_index(nodes[:-1], nodes[1:])

    def paths_batch(self, origins, destinations) -> tuple[np.ndarray, np.ndarray]:
        """Node sequences of many shortest paths at once, as CSR ``(offsets, nodes)``.

        Walks all predecessor chains together (one numpy step per hop), so
        the cost is ``O(max hops)`` vectorised steps, not a loop per path.
        Path ``i`` is ``nodes[offsets[i]:offsets[i+1]]`` from origin to destination.
        """
        o = np.asarray(origins, dtype=np.int64)
        d = np.asarray(destinations, dtype=np.int64)
        steps = [d.copy()]
        cur = d.copy()
        active = cur != o
        while active.any():
            nxt = np.where(active, self.pred[o, cur], cur)
            if (nxt[active] < 0).any():
                raise ParameterError("a requested path does not exist in the network")
            steps.append(np.where(active, nxt, -1))
            cur = nxt
            active = cur != o
        walk = np.stack(steps, axis=1)  # reversed paths, -1 padded
        lengths = (walk >= 0).sum(axis=1)
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        # Reverse each row's valid prefix: position j of row i holds walk[i, len_i-1-j].
        row = np.repeat(np.arange(len(o)), lengths)
        j = np.arange(offsets[-1]) - np.repeat(offsets[:-1], lengths)
        nodes = walk[row, lengths[row] - 1 - j].astype(np.int32)
        return offsets, nodes

    @property
    def nbytes(self) -> int:
        return int(self.dist.nbytes + self.pred.nbytes)


_DIGEST_FORMAT = "rpbench-apsp-sha256-1"


def apsp_digest(dist: np.ndarray, pred: np.ndarray) -> str:
    """SHA-256 of an all-pairs table: dtypes, shapes and the bytes of both arrays."""
    h = hashlib.sha256(f"{_DIGEST_FORMAT}|{dist.dtype.str}{dist.shape}|{pred.dtype.str}{pred.shape}|".encode())
    for arr in (dist, pred):
        h.update(np.ascontiguousarray(arr).data.cast("B"))
    return h.hexdigest()


@dataclass(frozen=True)
class _ApspFiles:
    """The three cache files of one network's all-pairs table."""

    stem: Path

    @classmethod
    def of(cls, network: RoadNetwork) -> _ApspFiles:
        return cls(cache_dir() / f"apsp-{network.content_hash}")

    @property
    def dist(self) -> Path:
        return Path(f"{self.stem}-dist.npy")

    @property
    def pred(self) -> Path:
        return Path(f"{self.stem}-pred.npy")

    @property
    def digest(self) -> Path:
        return Path(f"{self.stem}.sha256")

    @property
    def lock(self) -> Path:
        """Held by the process building the table (:func:`~rpbench.files.paths.builder_lock`)."""
        return Path(f"{self.stem}.lock")

    def load_verified(self, n_nodes: int) -> tuple[tuple[np.ndarray, np.ndarray] | None, str]:
        """``((dist, pred), "")`` when the cached table checks out, else ``(None, what is wrong)``.

        What is wrong is ``""`` when nothing was ever cached (a first build is
        not worth a note).
        """
        files = (self.dist, self.pred, self.digest)
        if not any(p.exists() for p in files):
            return None, ""
        if not self.digest.is_file():
            return None, "have no digest file (written by an older rpbench, or interrupted)"
        if not (self.dist.is_file() and self.pred.is_file()):
            return None, "are incomplete (an array file is missing)"
        try:
            # Plain ndarray views of the memory maps: indexing avoids numpy.memmap's per-call overhead.
            dist = np.asarray(np.load(self.dist, mmap_mode="r"))
            pred = np.asarray(np.load(self.pred, mmap_mode="r"))
            expected = self.digest.read_text(encoding="ascii").strip()
        except (OSError, ValueError, EOFError) as exc:
            return None, f"are unreadable ({one_line(exc)})"
        want = (n_nodes, n_nodes)
        if dist.shape != want or pred.shape != want or dist.dtype != np.float64 or pred.dtype != np.int32:
            return None, (
                f"hold {dist.dtype}{dist.shape} and {pred.dtype}{pred.shape} arrays, expected "
                f"float64{want} and int32{want}"
            )
        if apsp_digest(dist, pred) != expected:
            return None, f"do not match their SHA-256 digest {self.digest.name} (changed on disk)"
        return (dist, pred), ""

    def save(self, dist: np.ndarray, pred: np.ndarray) -> None:
        """Write both arrays, then their digest (so a digest always describes complete arrays)."""
        for path, write in (
            (self.dist, lambda fh: np.save(fh, dist)),
            (self.pred, lambda fh: np.save(fh, pred)),
            (self.digest, lambda fh: fh.write(apsp_digest(dist, pred).encode() + b"\n")),
        ):
            try:
                _atomic_write(path, write)
            except OSError as exc:
                raise cache_write_error(path, exc) from None


def _atomic_write(path: Path, write) -> None:
    """Write through ``write(file)`` into a temporary file renamed over ``path``; no leftover on failure."""
    tmp = temporary_file(path)  # carries the pid: a dead writer's leftover is swept (rpbench.files.paths)
    try:
        with open(tmp, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


# -------------------------------------------------------------------- snapping
SNAP_RULES = ("l1_degrees", "nearest")


def snap(network: RoadNetwork, lon, lat, *, rule: str = "l1_degrees") -> tuple[np.ndarray, np.ndarray]:
    """Snap WGS84 points to network nodes; return (node index, snap distance in m).

    ``l1_degrees`` is the authors' rule (smallest |Δlon| + |Δlat|; SOURCE.md
    reports it reproduces 1,765 of their 1,766 snapped origins).
    ``nearest`` is the true nearest node by great-circle distance (a k-d
    tree over unit vectors, whose chord length is monotone in arc length).
    """
    lon = np.asarray(lon, dtype=float)
    lat = np.asarray(lat, dtype=float)
    if rule == "l1_degrees":
        idx = np.empty(len(lon), dtype=np.int32)
        chunk = max(1, 2_000_000 // max(network.n_nodes, 1))
        for s in range(0, len(lon), chunk):
            cost = np.abs(lon[s : s + chunk, None] - network.lon[None, :]) + np.abs(
                lat[s : s + chunk, None] - network.lat[None, :]
            )
            idx[s : s + chunk] = np.argmin(cost, axis=1)
    elif rule == "nearest":
        _, idx = _unit_vector_tree(network).query(_unit_vectors(lon, lat))
        idx = np.asarray(idx, dtype=np.int32)
    else:
        raise ParameterError(f"unknown snapping rule {rule!r}; expected one of {', '.join(SNAP_RULES)}")
    return idx, great_circle_m(lon, lat, network.lon[idx], network.lat[idx])


def _unit_vectors(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    lam, phi = np.radians(lon), np.radians(lat)
    return np.column_stack([np.cos(phi) * np.cos(lam), np.cos(phi) * np.sin(lam), np.sin(phi)])


def _unit_vector_tree(network: RoadNetwork) -> cKDTree:
    tree = network._index.get("kdtree")
    if tree is None:
        tree = cKDTree(_unit_vectors(network.lon, network.lat))
        network._index["kdtree"] = tree
    return tree
