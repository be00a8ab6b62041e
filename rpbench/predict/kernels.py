"""Compiled sweeps over the seeker lists (numba): the inner loops of :mod:`.fixed_point` and :mod:`.savings`.

Every fixed-point iteration walks all stored (seeker, taker class) pairs in
each seeker's priority order, about 282 M pairs for the 21-day month table.
In numpy that walk needs a gather, a segmented cumulative sum, an ``exp`` and
a weighted ``bincount`` per pair and several full-length temporaries; here it
is one pass that keeps the running product ``λ_s Π_{c' ≻_s c} Q_c'`` in a
register (a multiplication per pair instead of an ``exp``) and allocates
nothing.  The per-seeker total ``log(1 - p_s) = Σ_c log Q_c`` is summed in
log space beside it, exactly as before, so ``p_s`` keeps its relative
precision when it is tiny.

The kernels take flat CSR arrays (``off`` of length ``m + 1`` local to the
chunk, ``cls`` int32) so a caller can stream a memory-mapped structure chunk
by chunk.  ``cache=True`` stores the machine code beside this module (or in
``NUMBA_CACHE_DIR``), so only the first run on a machine pays the
compilation (a few seconds).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, nogil=True)
def sweep_chunk(off, cls, lam, q, log_q, h, log_not_paired):  # pragma: no cover - compiled
    """Seekers ``0..m-1`` of a chunk: ``h[c] += λ_s Π_{c' ≻_s c} Q_c'`` and ``log_not_paired[s] = Σ log Q_c``.

    ``off`` (int64, m+1) are the seekers' pair offsets into ``cls``; ``lam``
    and ``log_not_paired`` are per seeker; ``q``, ``log_q`` and ``h`` per class.
    Seekers are walked two at a time, interleaved: their running products are
    two independent multiplication chains, which the processor overlaps with
    the class lookups (about 17 % faster than one seeker at a time).
    """
    m = len(off) - 1
    s = 0
    while s + 1 < m:
        weight_a, weight_b = lam[s], lam[s + 1]
        total_a = total_b = 0.0
        i, end_a = off[s], off[s + 1]
        j, end_b = off[s + 1], off[s + 2]
        while i < end_a and j < end_b:
            c = cls[i]
            d = cls[j]
            h[c] += weight_a
            weight_a *= q[c]
            total_a += log_q[c]
            h[d] += weight_b
            weight_b *= q[d]
            total_b += log_q[d]
            i += 1
            j += 1
        log_not_paired[s] = _walk(i, end_a, cls, weight_a, total_a, q, log_q, h)       # the longer list's rest
        log_not_paired[s + 1] = _walk(j, end_b, cls, weight_b, total_b, q, log_q, h)
        s += 2
    if s < m:
        log_not_paired[s] = _walk(off[s], off[s + 1], cls, lam[s], 0.0, q, log_q, h)


@njit(cache=True, nogil=True, inline="always")
def _walk(i, end, cls, weight, total, q, log_q, h):  # pragma: no cover - compiled
    """One seeker's pairs ``i..end-1`` from running product ``weight`` and log sum ``total``; the final sum."""
    while i < end:
        c = cls[i]
        h[c] += weight
        weight *= q[c]
        total += log_q[c]
        i += 1
    return total


@njit(cache=True, parallel=True)
def sweep_chunks(off, cls, lam, q, log_q, chunk_start, chunk_h, log_not_paired):  # pragma: no cover
    """:func:`sweep_chunk` over fixed chunks of seekers, in parallel threads.

    Chunk k (seekers ``chunk_start[k]..chunk_start[k+1]-1``) sums into its own
    row ``chunk_h[k]``; the caller adds the rows in chunk order, so the result
    does not depend on the number of threads nor on their scheduling.
    """
    for k in prange(len(chunk_start) - 1):
        s0, s1 = chunk_start[k], chunk_start[k + 1]
        chunk_h[k, :] = 0.0
        sweep_chunk(off[s0:s1 + 1], cls, lam[s0:s1], q, log_q, chunk_h[k], log_not_paired[s0:s1])


@njit(cache=True, nogil=True)
def savings_chunk(off, cls, saving, shared, detour, lam, q, log_q, one_minus_q, by_class, by_seeker,
                  log_not_paired):  # pragma: no cover - compiled
    """:func:`sweep_chunk` that also sums the pair quantities of the savings pass (§2.7).

    Per class c: ``by_class[c, 0..3] += w · (1, E, shared, detour)`` (column 0
    is H_c); per seeker s: ``by_seeker[s, 0..3] += w (1 - Q_c) · (1, E, shared,
    detour)``, with ``w = λ_s Π_{c' ≻_s c} Q_c'`` (so ``w (1 - Q_c)`` is the
    pairing rate of s with class c, telescoped).  Class rows are contiguous so
    that one cache line serves the four sums.
    """
    for s in range(len(off) - 1):
        weight = lam[s]
        total = 0.0
        rate = rate_e = rate_sh = rate_det = 0.0
        for i in range(off[s], off[s + 1]):
            c = cls[i]
            e, sh, det = saving[i], shared[i], detour[i]
            by_class[c, 0] += weight
            by_class[c, 1] += weight * e
            by_class[c, 2] += weight * sh
            by_class[c, 3] += weight * det
            pair = weight * one_minus_q[c]
            rate += pair
            rate_e += pair * e
            rate_sh += pair * sh
            rate_det += pair * det
            weight *= q[c]
            total += log_q[c]
        log_not_paired[s] = total
        by_seeker[s, 0] += rate
        by_seeker[s, 1] += rate_e
        by_seeker[s, 2] += rate_sh
        by_seeker[s, 3] += rate_det


@njit(cache=True, parallel=True)
def savings_chunks(off, cls, saving, shared, detour, lam, q, log_q, one_minus_q, chunk_start, by_class_parts,
                   by_seeker, log_not_paired):  # pragma: no cover - compiled
    """:func:`savings_chunk` over a few consecutive chunks in parallel threads; chunk k sums its
    classes into ``by_class_parts[k]`` (fixed, so the result does not depend on the threads)."""
    for k in prange(len(chunk_start) - 1):
        s0, s1 = chunk_start[k], chunk_start[k + 1]
        savings_chunk(off[s0:s1 + 1], cls, saving, shared, detour, lam[s0:s1], q, log_q, one_minus_q,
                      by_class_parts[k], by_seeker[s0:s1], log_not_paired[s0:s1])


@njit(cache=True, nogil=True)
def net_saving_keys(rows, start, n, piece_g, kappa, tie_rank, tie_bits, q_bits, grid, q_limit,
                    keys):  # pragma: no cover - compiled
    """Sort keys ``row | quantised descending (E - pk) | tie rank`` of the pieces' entries (see ``match_sets``).

    The arithmetic is the same IEEE sequence as the numpy packing: ``prio =
    g + κ``, ``desc = prio · (-grid) + 2^(q_bits-1)``, truncated to an integer.
    Returns False (keys unusable) when a priority lies outside ``(-q_limit, q_limit)``.
    """
    shift_tie = np.uint64(tie_bits)
    shift_row = np.uint64(q_bits + tie_bits)
    half = float(1 << (q_bits - 1))
    e = 0
    for j in range(len(n)):
        row = np.uint64(rows[j]) << shift_row
        g = piece_g[j]
        for col in range(start[j], start[j] + n[j]):
            prio = g + kappa[col]
            if not abs(prio) < q_limit:
                return False
            desc = prio * -grid + half
            keys[e] = (np.uint64(desc) << shift_tie) | np.uint64(tie_rank[col]) | row
            e += 1
    return True


@njit(cache=True, nogil=True)
def decode_entries(keys, tie_bits, tie_col, rows, start, n, piece_g, piece_shared, piece_detour, group_cls,
                   group_a, scratch, cls_out, saving_out, shared_out, detour_out):  # pragma: no cover
    """Write the sorted entries' columns from their keys.

    The pieces come grouped by row, and the sorted keys of row r occupy the
    same span as r's pieces' entries; within a row each survivor belongs to
    one piece, which ``scratch[survivor]`` records before the row is decoded.
    """
    mask = (np.uint64(1) << np.uint64(tie_bits)) - np.uint64(1)
    e = 0
    j = 0
    m = len(n)
    while j < m:
        j1 = j
        count = 0
        while j1 < m and rows[j1] == rows[j]:
            for col in range(start[j1], start[j1] + n[j1]):
                scratch[col] = j1
            count += n[j1]
            j1 += 1
        for i in range(e, e + count):
            col = tie_col[np.int64(keys[i] & mask)]
            p = scratch[col]
            cls_out[i] = group_cls[col]
            saving_out[i] = piece_g[p] - group_a[col]
            shared_out[i] = piece_shared[p]
            detour_out[i] = piece_detour[p]
        e += count
        j = j1
