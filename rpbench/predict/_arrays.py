"""Small vectorised helpers for CSR-style (segmented) arrays."""

from __future__ import annotations

import numpy as np


def expand_ranges(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(lo[i], hi[i])`` over i (empty ranges allowed), as int64."""
    lo = np.asarray(lo, dtype=np.int64)
    n = np.maximum(np.asarray(hi, dtype=np.int64) - lo, 0)
    total = int(n.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    starts = np.cumsum(n) - n
    return np.arange(total, dtype=np.int64) - np.repeat(starts - lo, n)


def offsets_from_counts(counts: np.ndarray) -> np.ndarray:
    """CSR offsets (length n+1, int64) from per-segment counts."""
    return np.concatenate([[0], np.cumsum(np.asarray(counts, dtype=np.int64))]).astype(np.int64)


def segment_sums(values: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Sum of ``values[offsets[i]:offsets[i+1]]`` per segment (0 for empty segments)."""
    out = np.zeros(len(offsets) - 1, dtype=np.result_type(values, np.float64))
    lens = np.diff(offsets)
    nonempty = np.flatnonzero(lens > 0)
    if len(nonempty):
        out[nonempty] = np.add.reduceat(values, offsets[nonempty])
    return out


def segment_exclusive_cumsum(values: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Per segment, the sum of the earlier values of the same segment (0 at each segment start).

    One cumulative sum over all segments that restarts at each segment start:
    the shifted values are corrected there by the previous segment's total,
    so the running sum never grows beyond one segment's magnitude (a plain
    global cumsum minus a base would lose precision on long arrays).
    """
    values = np.asarray(values, dtype=np.float64)
    out = np.zeros(len(values))
    if len(values) == 0:
        return out
    out[1:] = values[:-1]
    starts = offsets[:-1][np.diff(offsets) > 0]
    totals = np.add.reduceat(values, starts)
    out[starts[1:]] -= totals[:-1]
    out[starts[0]] = 0.0
    return np.cumsum(out, out=out)
