"""Which node pairs lie within a distance: a table that pre-filters pick-up candidates.

A round's candidate search asks, for every (vehicle, passenger) pair, whether
``pre + l(node, origin) <= R̄``.  Gathering ``l`` for all pairs from the
all-pairs table (120 MB for Haikou, one row per vehicle node) costs about one
cache miss per pair, while only a few per cent of node pairs are within R̄.
Since ``pre >= 0``, a pair can only qualify if ``l(node, origin) <= R̄``
alone.  A boolean table stored by *destination* answers that for a round from
one short row per passenger origin (3.9 kB for Haikou), which stays in cache;
the exact test then runs on the few pairs that pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class NearTable:
    """``reach[v, u]`` is True when ``dist[u, v] <= threshold_m`` (row: the destination node)."""

    dist: np.ndarray
    threshold_m: float
    reach: np.ndarray  # bool (n, n)

    #: Source rows compared per block while transposing (bounds the temporary to block x n booleans).
    BLOCK = 256

    @classmethod
    def build(cls, dist: np.ndarray, threshold_m: float) -> NearTable:
        n = dist.shape[0]
        reach = np.empty((dist.shape[1], n), dtype=bool)
        for start in range(0, n, cls.BLOCK):  # blockwise: a whole-table bool transpose is 4x slower
            reach[:, start : start + cls.BLOCK] = (dist[start : start + cls.BLOCK] <= threshold_m).T
        return cls(dist, float(threshold_m), reach)

    def mask(self, from_nodes: np.ndarray, to_nodes: np.ndarray) -> np.ndarray:
        """Boolean ``(len(to_nodes), len(from_nodes))``: ``dist[from, to] <= threshold`` (rows: ``to_nodes``)."""
        return self.reach[np.asarray(to_nodes, dtype=np.int64)][:, np.asarray(from_nodes, dtype=np.int64)]


_last: NearTable | None = None


def near_table(dist: np.ndarray, threshold_m: float) -> NearTable:
    """The :class:`NearTable` of ``dist`` (the same array object) at ``threshold_m``, built once and kept.

    One table is kept: a simulation asks for the same one every round, and a
    new distance table or threshold replaces it.
    """
    global _last
    if _last is None or _last.dist is not dist or _last.threshold_m != float(threshold_m):
        _last = NearTable.build(dist, threshold_m)
    return _last
