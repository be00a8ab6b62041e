"""Exhaustive optimum of tiny models: every 0/1 vector, vectorised."""

from __future__ import annotations

import numpy as np

MAX_COLS = 16


def brute_force(model) -> tuple[float, int] | None:
    """(best objective, its number of columns) — the lexicographic (pairs, value) optimum for Oracle-2 —
    or ``None`` when no 0/1 vector is feasible."""
    n = model.n_cols
    assert n <= MAX_COLS, "brute force is for tiny models"
    X = ((np.arange(2**n)[:, None] >> np.arange(n)) & 1).astype(np.int64)
    cover = X @ model.incidence().T.toarray().astype(np.int64)
    ok = (cover <= 1).all(axis=1) & (cover[:, model.row_exact()] == 1).all(axis=1)
    if not ok.any():
        return None
    value = X[ok] @ model.values
    count = X[ok].sum(axis=1)
    if getattr(model, "objective", "weight") == "cardinality_then_weight":
        k = count.max()
        return float(value[count == k].max()), int(k)
    best = value.argmax()
    return float(value[best]), int(count[best])
