"""Exact separation of the blossom inequalities of the matching polytope (Padberg and Rao 1982).

Edmonds (1965): the convex hull of the matchings of ``G = (V, E)`` is

    x >= 0,    x(δ(v)) <= 1 (v in V),    x(E(S)) <= (|S| - 1) / 2 (S ⊆ V odd, |S| >= 3).

With the vertex slacks ``s_v = 1 - x(δ(v)) >= 0``, summing the degrees over ``S`` gives
``2 x(E(S)) = |S| - s(S) - x(δ(S))``, so the blossom inequality of ``S`` reads ``x(δ(S)) + s(S) >= 1``: the
capacity of the cut that ``S`` leaves in ``G'``, ``G`` plus a vertex ``d`` joined to every ``v`` with capacity
``s_v`` (edges with capacity ``x_e``).  With ``T = V`` (``|V|`` even) or ``V + d`` (``|V|`` odd), the cuts
``δ'(S)`` with ``|S ∩ T|`` odd are exactly those of the odd ``S ⊆ V`` (taking the side without ``d``), so an
inequality is violated if and only if the minimum ``T``-odd cut of ``G'`` is below 1; Padberg and Rao show that
one minimum ``T``-odd cut is a fundamental cut of any Gomory–Hu tree of ``G'``.  Sets of 1 vertex are never
violated (their cut is ``x(δ(v)) + s_v = 1``).

Only the support ``x > 0`` matters, split into its connected components: a violated ``S`` has cut below 1,
and the parts of ``S`` in the components sum to an odd size, so one part is odd and its own cut (at most
``S``'s, every part's cut is >= 0) is below 1 too.  The Gomory–Hu trees are built by Gusfield's algorithm
(n - 1 maximum flows, scipy's, on capacities scaled to integers); each set returned is checked violated on
the unscaled ``x`` here, so the scaling can only cost a set, never yield a wrong one.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, maximum_flow

#: Capacities are scaled to integers for scipy's maximum flow (a cut's rounding error is below its edges'
#: count over this).
FLOW_SCALE = 1 << 20
#: A blossom inequality counts as violated when ``x(E(S))`` exceeds ``(|S| - 1)/2`` by more than this (the LP's
#: own tolerance is far below it; a smaller violation would not move the bound).
VIOLATION_TOL = 1e-6


def inside_weight(a: np.ndarray, b: np.ndarray, x: np.ndarray, members: np.ndarray, n: int) -> float:
    """``x(E(S))``: the total of ``x`` over the edges ``(a, b)`` with both ends in ``members``."""
    mask = np.zeros(n, bool)
    mask[members] = True
    return float(x[mask[a] & mask[b]].sum())


def is_violated_blossom(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray, members: np.ndarray) -> bool:
    """Whether ``members`` is an odd set of at least 3 vertices whose blossom inequality ``x`` violates."""
    size = len(np.unique(members))
    return size >= 3 and size % 2 == 1 and inside_weight(a, b, x, members, n) > (size - 1) / 2 + VIOLATION_TOL


def violated_blossoms(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
    """Odd vertex sets whose blossom inequalities ``x`` (on the edges ``(a, b)``, ``x(δ(v)) <= 1``) violates:
    of every component of the support, each violated fundamental cut of its Gomory–Hu tree (a laminar family,
    holding a most violated set).  Empty only when ``x`` satisfies every blossom inequality (module docstring)
    up to the scaling of the flows."""
    support = np.flatnonzero(x > 0)
    if not len(support):
        return []
    a, b, x = a[support], b[support], x[support]
    _, label = connected_components(sp.coo_matrix((x, (a, b)), shape=(n, n)), directed=False)
    size = np.bincount(label[np.unique(np.r_[a, b])], minlength=label.max() + 1)  # vertices a component
    order = np.argsort(label[a], kind="stable")
    first = np.searchsorted(label[a][order], np.arange(len(size) + 1))
    found: list[np.ndarray] = []
    for comp in np.flatnonzero(size >= 3).tolist():
        inside = order[first[comp] : first[comp + 1]]
        found += _component_blossoms(n, a[inside], b[inside], x[inside])
    return found


def _component_blossoms(n: int, a: np.ndarray, b: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
    """:func:`violated_blossoms` within one connected component ``(a, b)`` of the support."""
    vertices, local = np.unique(np.r_[a, b], return_inverse=True)
    k = len(vertices)
    la, lb = local[: len(a)] + 1, local[len(a) :] + 1  # node 0 is the dummy d
    slack = np.maximum(1.0 - np.bincount(np.r_[la, lb], weights=np.r_[x, x], minlength=k + 1)[1:], 0.0)
    dummy_edge = np.flatnonzero(slack > 0)
    u = np.r_[la, dummy_edge + 1]
    v = np.r_[lb, np.zeros(len(dummy_edge), np.int64)]
    cap = np.rint(np.r_[x, slack[dummy_edge]] * FLOW_SCALE).astype(np.int64)
    parent, _ = _gomory_hu_tree(k + 1, u, v, cap)
    out = []
    for side in _fundamental_sides(parent):
        if len(side) >= 3 and len(side) % 2 == 1:
            members = vertices[side - 1]
            if is_violated_blossom(n, a, b, x, members):
                out.append(members)
    return out


def _gomory_hu_tree(k: int, u: np.ndarray, v: np.ndarray, cap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each node's parent in a Gomory–Hu cut tree of the undirected graph ``(u, v)`` with capacities ``cap`` on
    nodes ``0..k-1``, rooted at 0, and the capacity of its tree edge (Gusfield 1990, the cut-tree variant:
    k - 1 maximum flows on the graph itself, no contractions)."""
    both = sp.csr_matrix((np.r_[cap, cap], (np.r_[u, v], np.r_[v, u])), shape=(k, k))
    both.sum_duplicates()
    both.data = both.data.astype(np.int32)
    parent = np.zeros(k, np.int64)
    flow_of = np.zeros(k, np.int64)
    for s in range(1, k):
        t = int(parent[s])
        side, value = _min_cut_side(both, s, t)
        flow_of[s] = value
        move = side & (parent == t)
        move[s] = False
        parent[move] = s
        if side[parent[t]]:
            parent[s], parent[t] = parent[t], s
            flow_of[s], flow_of[t] = flow_of[t], value
    return parent, flow_of


def _min_cut_side(capacity: sp.csr_matrix, s: int, t: int) -> tuple[np.ndarray, int]:
    """The source side of a minimum ``s``-``t`` cut (the nodes the residual graph reaches from ``s``) and its
    capacity."""
    result = maximum_flow(capacity, s, t)
    residual = (capacity - result.flow).tocsr()
    residual.data = (residual.data > 0).astype(np.int8)
    residual.eliminate_zeros()
    reached = breadth_first_order(residual, s, directed=True, return_predecessors=False)
    side = np.zeros(capacity.shape[0], bool)
    side[reached] = True
    return side, int(result.flow_value)


def _fundamental_sides(parent: np.ndarray) -> list[np.ndarray]:
    """For every node but the root 0 of the tree ``parent``, the nodes of its subtree (the side of its tree
    edge's cut without the root)."""
    k = len(parent)
    tree = sp.csr_matrix((np.ones(k - 1), (parent[1:], np.arange(1, k))), shape=(k, k))
    top_down = breadth_first_order(tree, 0, directed=True, return_predecessors=False)
    members: list[list[int]] = [[i] for i in range(k)]
    for node in top_down[::-1].tolist():  # children before their parents
        if node:
            members[int(parent[node])] += members[node]
    return [np.array(members[i], np.int64) for i in range(1, k)]
