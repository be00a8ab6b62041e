"""A trip-packing optimum without branch and bound, when it is provably the only one.

When a model has exactly one optimal solution, every exact solver returns that solution, so a
simulation cannot tell how it was found. With ties the MIP's own pick matters (the repair in
``sim/ties.py`` does not settle every tie), so :func:`unique_optimum` answers only with a proof of
uniqueness, and ``None`` otherwise: the caller then solves the unchanged MIP.

The candidate ``S`` is the LP relaxation's vertex when it is integral. Every row is "<= 1", values
are integers, and the proof is checked here in float64 with a margin many orders of magnitude above
rounding error, never taken from the solver's word:

1. a dual ``y >= 0``, zero on the rows ``S`` leaves free, with reduced costs ``d = c - Aᵀy``
   positive on ``S`` and negative off it. For any other 0/1 point ``x``,
   ``c·S - c·x = d·(S - x) + Σ_i y_i (1 - (Ax)_i) > 0``. HiGHS's dual is usually tight on a
   runner-up column (degenerate), so ``ε`` is first added on every covered row, small enough to
   keep ``S``'s reduced costs positive.
2. failing that, weak duality on ``max Σ_{j∉S} x_j + Σ_{j∈S} (1 - x_j)`` (the Hamming distance to
   ``S``) over ``Ax <= 1, c·x >= c·S - 1/2, 0 <= x <= 1``: a bound below 1 leaves no other 0/1
   point worth as much as ``S``.

Columns of negative value are in no optimum and are left out of the LPs; rows no column uses are
dropped. ``y`` extends to the full model by zeros, and a dropped column's reduced cost is then
below its negative value, so both proofs hold for the model as given.
"""

from __future__ import annotations

import numpy as np

#: Relative slack for float64 sums of a few terms (rounding error is below 1e-15 relative).
MARGIN = 1e-9


def unique_optimum(model, highs) -> np.ndarray | None:
    """The chosen columns of ``model``'s only optimum, or ``None`` when that is not proven.

    ``model``: a packing model whose rows are all "<= 1" (trip packing); ``highs``: a
    ``highspy.Highs`` with LP options set and no model, whose model this replaces.
    """
    import highspy

    c = model.values
    col_start, col_rows = model.column_rows()
    keep = np.flatnonzero(c >= 0)
    if len(keep) == 0:
        return keep  # x = 0 is the only optimum
    count = np.diff(col_start)
    if len(keep) < len(c):  # rare: most rounds have no negative column
        count = count[keep]
        entries = np.repeat(col_start[keep] - np.cumsum(count) + count, count) + np.arange(count.sum())
        col_rows, c = col_rows[entries], c[keep]
        col_start = np.zeros(len(keep) + 1, dtype=np.int64)
        np.cumsum(count, out=col_start[1:])
    used = np.zeros(model.n_rows, dtype=bool)
    used[col_rows] = True
    index = np.cumsum(used, dtype=np.int32) - 1  # rows no column uses are dropped
    col_rows = index[col_rows]
    n, m = len(keep), int(index[-1]) + 1
    if m == len(col_rows):  # disjoint trips: take every one that has value
        return keep if (c > 0).all() else None

    inf = highspy.kHighsInf
    highs.passModel(
        n,
        m,
        len(col_rows),
        int(highspy.MatrixFormat.kColwise),
        int(highspy.ObjSense.kMaximize),
        0.0,
        c,
        np.zeros(n),
        np.ones(n),
        np.full(m, -inf),
        np.ones(m),
        col_start.astype(np.int32),
        col_rows,
        np.ones(len(col_rows)),
        np.zeros(n, dtype=np.int32),
    )
    highs.run()
    if highs.getModelStatus().name != "kOptimal":
        return None
    solution = highs.getSolution()
    x = np.asarray(solution.col_value)
    chosen = x > 0.5
    if np.abs(x - chosen).max() > 1e-6 or not chosen.any():
        return None  # fractional vertex, or only zero values (a tie)
    covered = np.bincount(col_rows[np.repeat(chosen, count)], minlength=m)
    if covered.max() > 1:
        return None

    if _strict_dual(c, col_rows, col_start, count, chosen, covered > 0, np.asarray(solution.row_dual)):
        return keep[chosen]
    if _closest_rival_far(highs, c, col_rows, col_start, m, chosen):
        return keep[chosen]
    return None


def _row_sums(y: np.ndarray, col_rows: np.ndarray, col_start: np.ndarray) -> np.ndarray:
    """``Aᵀy``: per column, the sum of ``y`` over its rows (every column has a row)."""
    return np.add.reduceat(y[col_rows], col_start[:-1])


def _strict_dual(c, col_rows, col_start, count, chosen, covered, row_dual) -> bool:
    """Proof 1: a dual, nudged by ε on the covered rows, with strictly signed reduced costs."""
    y = np.where(covered, np.maximum(row_dual, 0.0), 0.0)
    d = c - _row_sums(y, col_rows, col_start)
    tol = MARGIN * (1.0 + np.abs(c).max() + 3.0 * y.max())
    slack = d[chosen]
    if (slack <= tol).any():
        return False
    y = np.where(covered, y + (slack / count[chosen]).min() / 2, 0.0)
    d = c - _row_sums(y, col_rows, col_start)
    tol = MARGIN * (1.0 + np.abs(c).max() + 3.0 * y.max())
    return bool((d[chosen] > tol).all() and (d[~chosen] < -tol).all())


def _closest_rival_far(highs, c, col_rows, col_start, m, chosen) -> bool:
    """Proof 2: no other 0/1 point within reach of ``S``'s value (the LP just solved, warm-started)."""
    import highspy

    n = len(c)
    floor = float(c[chosen].sum()) - 0.5
    every = np.arange(n, dtype=np.int32)
    g = np.where(chosen, -1.0, 1.0)
    highs.addRow(floor, highspy.kHighsInf, n, every, c)
    highs.changeColsCost(n, every, g)
    highs.run()
    w = np.asarray(highs.getSolution().row_dual)
    # Any u >= 0 on the "<= 1" rows and lam <= 0 on the ">= floor" row bound g·x from above.
    u = np.maximum(w[:m], 0.0)
    lam = min(float(w[m]), 0.0)
    red = g - _row_sums(u, col_rows, col_start) - lam * c
    bound = chosen.sum() + u.sum() + lam * floor + np.maximum(red, 0.0).sum()
    scale = chosen.sum() + u.sum() + abs(lam) * (abs(floor) + np.abs(c).sum()) + 2.0 * n
    return bool(bound + MARGIN * scale < 0.5)
