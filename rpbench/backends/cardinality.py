"""Maximum-cardinality matching in a general graph, with its Tutte-Berge certificate.

Oracle-2's first stage (docs/algorithms.md §4: most pairs) is a maximum-cardinality
matching.  Weighted solvers handle it badly — every weight is the same, and
sparse blossom or a MIP then crawl — so it gets its own exact algorithm:

* Edmonds' blossom search for an augmenting path, one exposed root at a time,
  from a greedy (minimum-degree) start or a caller's matching.  Blossom bases
  live in a union-find, so a search costs ``O(m α(n))`` in the part of the
  graph it explores rather than ``O(n)`` per contraction.
* A root whose search fails has a *Hungarian tree*: no matching edge leaves
  it and no later augmenting path can enter it (Edmonds 1965), so its
  vertices are deleted for good.  Failed searches therefore cost ``O(m)`` in
  total, and only the (few) successful ones are repeated work.

The result is certified independently of the search.  ``U`` = the inner
vertices of all Hungarian trees is a Tutte-Berge set: every outer blossom is
an odd component of ``G - U`` and every other vertex is matched inside
``G - U``, so ``ν(G) <= (n - odd(G - U) + |U|) / 2`` (Tutte-Berge), which
:func:`tutte_berge_bound` recomputes with a vectorised component count.  The
matching attains it, hence is maximum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from rpbench.exceptions import SolverError


@dataclass(frozen=True)
class CardinalityMatching:
    """A maximum matching as ``mate`` (``-1`` = exposed) and the Tutte-Berge set proving it."""

    mate: np.ndarray
    tutte_set: np.ndarray

    @property
    def size(self) -> int:
        return int((self.mate >= 0).sum() // 2)


def adjacency(n: int, a: np.ndarray, b: np.ndarray) -> sp.csr_matrix:
    """Symmetric 0/1 CSR adjacency of the edges ``(a_i, b_i)`` (duplicates merged)."""
    g = sp.csr_matrix((np.ones(2 * len(a), np.int8), (np.concatenate([a, b]), np.concatenate([b, a]))), shape=(n, n))
    g.sum_duplicates()
    return g


def greedy_matching(g: sp.csr_matrix) -> np.ndarray:
    """A maximal matching, low-degree vertices first (they have the fewest chances later)."""
    n = g.shape[0]
    deg_arr = np.diff(g.indptr)
    deg = deg_arr.tolist()
    mate = [-1] * n
    indptr, indices = g.indptr.tolist(), g.indices.tolist()
    for v in np.argsort(deg_arr, kind="stable").tolist():
        if mate[v] >= 0:
            continue
        best, best_deg = -1, n
        for k in range(indptr[v], indptr[v + 1]):
            u = indices[k]
            if mate[u] < 0 and u != v and deg[u] < best_deg:
                best, best_deg = u, deg[u]
        if best >= 0:
            mate[v], mate[best] = best, v
    return np.asarray(mate, np.int64)


def maximum_cardinality_matching(
    n: int, a: np.ndarray, b: np.ndarray, start: np.ndarray | None = None
) -> CardinalityMatching:
    """A maximum-cardinality matching of the graph ``(range(n), zip(a, b))``, certified.

    ``start`` (optional) is a matching to augment, as a ``mate`` array.  The
    result is checked against :func:`tutte_berge_bound` before it is returned.
    """
    a, b = np.asarray(a, np.int64), np.asarray(b, np.int64)
    g = adjacency(n, a, b)
    if start is None:
        mate_arr = greedy_matching(g)
    else:
        mate_arr = np.asarray(start, np.int64).copy()
        _check_mate(n, a, b, mate_arr)
    adj = [row.tolist() for row in np.split(g.indices, g.indptr[1:-1])]
    mate = mate_arr.tolist()
    search = _BlossomSearch(adj, mate)
    inner: list[int] = []
    for root in range(n):
        if mate[root] < 0 and not search.deleted[root]:
            found = search.augment_from(root)
            if not found:
                inner.extend(search.hungarian_inner())
    result = CardinalityMatching(np.asarray(mate, np.int64), np.asarray(sorted(inner), np.int64))
    bound = tutte_berge_bound(n, a, b, result.tutte_set)
    if bound != result.size:  # cannot happen unless the search above is wrong: never pass it on
        raise SolverError(f"maximum-cardinality matching not certified: {result.size} pairs, Tutte-Berge bound {bound}")
    return result


def mate_of(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The ``mate`` array (``-1`` = unmatched) of the matching made of the pairs ``(a_i, b_i)``."""
    mate = np.full(n, -1, np.int64)
    mate[a], mate[b] = b, a
    return mate


def columns_of_mate(n: int, a: np.ndarray, b: np.ndarray, mate: np.ndarray) -> np.ndarray:
    """Indices ``i`` of the edges ``(a_i, b_i)`` that a ``mate`` array matches, in ascending order."""
    low = np.flatnonzero((mate >= 0) & (np.arange(n) < mate))
    return edge_indices(n, a, b, low, mate[low])


def edge_indices(n: int, a: np.ndarray, b: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Index of each pair ``{u_j, v_j}`` among the edges ``(a_i, b_i)``; SolverError if one is not an edge."""
    keys = np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)
    order = np.argsort(keys)
    want = np.minimum(u, v).astype(np.int64) * n + np.maximum(u, v)
    pos = np.minimum(np.searchsorted(keys[order], want), max(len(keys) - 1, 0))
    if len(want) and (len(keys) == 0 or np.any(keys[order][pos] != want)):
        raise SolverError("a matching algorithm matched two orders that are not a candidate pair")
    return np.sort(order[pos])


def tutte_berge_bound(n: int, a: np.ndarray, b: np.ndarray, tutte_set: np.ndarray) -> int:
    """``(n - odd(G - U) + |U|) // 2`` for ``U`` = ``tutte_set``: an upper bound on every matching (Tutte-Berge)."""
    from scipy.sparse.csgraph import connected_components

    keep = np.ones(n, bool)
    keep[tutte_set] = False
    a, b = np.asarray(a, np.int64), np.asarray(b, np.int64)
    both = keep[a] & keep[b]
    g = sp.csr_matrix((np.ones(int(both.sum()), np.int8), (a[both], b[both])), shape=(n, n))
    _, label = connected_components(g, directed=False)
    sizes = np.bincount(label[keep])
    odd = int((sizes % 2 == 1).sum())
    return (n - odd + len(tutte_set)) // 2


def _check_mate(n: int, a: np.ndarray, b: np.ndarray, mate: np.ndarray) -> None:
    if mate.shape != (n,) or np.any(mate >= n) or np.any(mate < -1):
        raise ValueError("start matching: expected a mate array of length n with values in -1..n-1")
    v = np.flatnonzero(mate >= 0)
    if np.any(mate[mate[v]] != v):
        raise ValueError("start matching is not a matching of the graph")
    try:
        edge_indices(n, a, b, v, mate[v])
    except SolverError:
        raise ValueError("start matching is not a matching of the graph") from None


class _BlossomSearch:
    """Edmonds' augmenting-path search from one root, blossoms contracted in a union-find.

    Labels: a vertex is *outer* (even distance from the root in the contracted
    tree; scanned) or *inner* (odd; reached over a non-matching edge).
    ``parent`` points from an inner vertex — and, after a contraction, from
    an outer one inside the blossom — to the vertex it was reached from, so
    the augmenting path can be read back through blossoms (as in the
    classic e-maxx formulation).  Every per-search array is reset only where
    the search touched it, keeping a search local to the part it explores.
    """

    def __init__(self, adj: list[list[int]], mate: list[int]):
        n = len(adj)
        self.adj, self.mate = adj, mate
        self.deleted = [False] * n
        self.parent = [-1] * n
        self.outer = [False] * n
        self.uf = list(range(n))  # union-find over blossoms
        self.base = list(range(n))  # base vertex of a union-find root's blossom
        self.stamp = [0] * n  # lowest-common-ancestor marks
        self.clock = 0
        self.touched: list[int] = []

    def _find(self, v: int) -> int:
        uf = self.uf
        r = v
        while uf[r] != r:
            r = uf[r]
        while uf[v] != r:  # path compression
            uf[v], v = r, uf[v]
        return r

    def _base(self, v: int) -> int:
        return self.base[self._find(v)]

    def _reset(self) -> None:
        parent, outer, uf, base = self.parent, self.outer, self.uf, self.base
        for v in self.touched:
            parent[v], outer[v], uf[v], base[v] = -1, False, v, v

    def augment_from(self, root: int) -> bool:
        """Augment along a path from exposed ``root``; False (tree left for :meth:`hungarian_inner`) if none."""
        self._reset()
        adj, mate, parent, outer, deleted = self.adj, self.mate, self.parent, self.outer, self.deleted
        touched = self.touched = [root]
        outer[root] = True
        queue = [root]
        head = 0
        while head < len(queue):
            v = queue[head]
            head += 1
            for to in adj[v]:
                if deleted[to] or mate[v] == to:
                    continue
                if outer[to]:
                    # both ends outer: an odd cycle, to contract unless already inside one blossom
                    if self._find(v) != self._find(to):
                        self._contract(v, to, queue)
                elif parent[to] < 0:  # unreached (inner vertices need nothing)
                    parent[to] = v
                    touched.append(to)
                    if mate[to] < 0:
                        self._flip(to)
                        return True
                    m = mate[to]
                    outer[m] = True
                    touched.append(m)
                    queue.append(m)
        return False

    def _flip(self, v: int) -> None:
        """Augment along the path ending at the exposed vertex ``v``."""
        mate, parent = self.mate, self.parent
        while v >= 0:
            pv = parent[v]
            nxt = mate[pv]
            mate[v], mate[pv] = pv, v
            v = nxt

    def _lca(self, x: int, y: int) -> int:
        self.clock += 1
        stamp, mate, parent, c = self.stamp, self.mate, self.parent, self.clock
        while True:
            x = self._base(x)
            stamp[x] = c
            if mate[x] < 0:
                break
            x = parent[mate[x]]
        while True:
            y = self._base(y)
            if stamp[y] == c:
                return y
            y = parent[mate[y]]

    def _contract(self, v: int, to: int, queue: list[int]) -> None:
        b = self._lca(v, to)
        merged: list[int] = []
        self._mark_path(v, b, to, merged, queue)
        self._mark_path(to, b, v, merged, queue)
        rb = self._find(b)
        for r in merged:
            self.uf[r] = rb
        self.base[rb] = b

    def _mark_path(self, v: int, b: int, child: int, merged: list[int], queue: list[int]) -> None:
        mate, parent, outer = self.mate, self.parent, self.outer
        while self._base(v) != b:
            m = mate[v]
            for r in (self._find(v), self._find(m)):
                merged.append(r)
            parent[v] = child
            child = m
            if not outer[m]:  # an inner vertex joins an outer blossom: scan it
                outer[m] = True
                queue.append(m)
            v = parent[m]

    def hungarian_inner(self) -> list[int]:
        """Delete the last (failed) search's tree and return its inner vertices (part of the Tutte set)."""
        inner = []
        for v in self.touched:
            self.deleted[v] = True
            if not self.outer[v]:
                inner.append(v)
        return inner
