"""Which node pairs lie within a distance: a bit table that pre-filters pick-up candidates.

A round's candidate search asks, for every (vehicle, passenger) pair, whether
``pre + l(node, origin) <= R̄``.  Gathering ``l`` for all pairs from the
all-pairs table (120 MB for Haikou) costs one cache miss per pair, while only
a few per cent of node pairs are within R̄.  Since ``pre >= 0``, a pair can
only qualify if ``l(node, origin) <= R̄`` alone, which one bit per node pair
answers from a table small enough to stay in cache (1.9 MB for Haikou); the
exact test then runs on the pairs that pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class NearTable:
    """Bit ``[u, v]`` is set when ``dist[u, v] <= threshold_m`` (rows packed little-endian)."""

    dist: np.ndarray
    threshold_m: float
    bits: np.ndarray          # uint8 (n, ceil(n / 8))

    @classmethod
    def build(cls, dist: np.ndarray, threshold_m: float) -> NearTable:
        bits = np.packbits(dist <= threshold_m, axis=1, bitorder="little")
        return cls(dist, float(threshold_m), bits)

    def mask(self, from_nodes: np.ndarray, to_nodes: np.ndarray) -> np.ndarray:
        """Boolean ``(len(to_nodes), len(from_nodes))``: ``dist[from, to] <= threshold`` (rows: ``to_nodes``)."""
        to = np.asarray(to_nodes, dtype=np.int64)[:, None]
        rows = np.asarray(from_nodes, dtype=np.int64)[None, :]
        bit = np.left_shift(np.uint8(1), (to & 7).astype(np.uint8))
        return (self.bits[rows, to >> 3] & bit) != 0


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
