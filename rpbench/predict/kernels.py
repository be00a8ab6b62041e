"""Compiled sweeps over the seeker lists (numba): the inner loops of :mod:`.fixed_point` and :mod:`.savings`.

Every fixed-point iteration walks all stored (seeker, taker class) pairs in
each seeker's priority order, about 282 M pairs for the 21-day month table.
In numpy that walk needs a gather, a segmented cumulative sum, an ``exp`` and
a weighted ``bincount`` per pair and several full-length temporaries; here it
is one pass that keeps the running product ``λ_s Π_{c' ≻_s c} Q_c'`` in a
register (a multiplication per pair instead of an ``exp``) and allocates
nothing.  The per-seeker total ``log(1 - p_s) = Σ_c log Q_c`` is summed in
log space beside it, so ``p_s`` keeps its relative precision when it is tiny.

The kernels take flat CSR arrays (``off`` of length W + 1, global pair
offsets) so a caller can stream a memory-mapped structure chunk by chunk.
Seekers are walked in *blocks* (:mod:`.blocks`): consecutive seekers whose
lists together name at most 65,536 taker classes.  A block's class values are
gathered into small arrays first and the pairs index them with block-local
16-bit numbers, so the per-pair lookups hit a few hundred kilobytes that stay
in the core's cache instead of megabytes spread over the whole class table,
and a pair costs two bytes of the stream.  A class's Q, log Q and H share one
row of that table, so a pair touches one cache line of it.  ``cache=True``
stores the machine code beside this module (or in ``NUMBA_CACHE_DIR``), so
only the first run on a machine pays the compilation (a few seconds).  Every
kernel releases the GIL (``nogil``); the callers run chunks of blocks in a
thread pool rather than with numba's ``parallel=True``, whose compilation
would add several seconds to a machine's first run.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Row widths of the block tables (``loc``), flat arrays of ``width x ROW`` float64: a constant power of two
#: makes a row's address a shift of the class number, where a 2-D array's stride would cost a multiply.
SWEEP_ROW = np.uint64(4)  # Q, log Q, the block's H sum, padding: two rows per 64-byte cache line
SAVINGS_ROW = np.uint64(8)  # Q, log Q, 1 - Q, four class sums, l(h, d_A): one row per cache line
CELL_ROW = np.uint64(8)  # per node d_A: a cell's bound, g_FOLO, g_FOFO, FOFO's shared and detour, its seeker, padding
_ONE = np.uint64(1)


@njit(cache=True, nogil=True)
def sweep_blocks(
    off, local, lam, q, log_q, block_seeker, block_cls, block_cls_off, b0, b1, h, log_not_paired, loc
):  # pragma: no cover - compiled
    """Blocks ``b0..b1-1``: ``h[c] += λ_s Π_{c' ≻_s c} Q_c'`` and ``log_not_paired[s] = Σ log Q_c``.

    Block b holds seekers ``block_seeker[b]..block_seeker[b+1]-1`` and the
    classes ``block_cls[block_cls_off[b]:block_cls_off[b+1]]`` their lists
    name; ``local`` indexes a pair's class within its block (see
    :mod:`.blocks`).  A block's ``Q`` and ``log Q`` are gathered into the rows
    of ``loc`` (flat, :data:`SWEEP_ROW` per class: Q, log Q, the block's H sum,
    padding), so a pair's three values share one cache line of a table that
    fits the core's cache, and ``H`` is scattered back per block.
    """
    for b in range(b0, b1):
        k0 = block_cls_off[b]
        k = block_cls_off[b + 1] - k0
        _gather_block(block_cls[k0 : k0 + k], (q, log_q), loc, SWEEP_ROW)
        _sweep_seekers(off, local, lam, loc, log_not_paired, block_seeker[b], block_seeker[b + 1])
        for j in range(k):
            h[block_cls[k0 + j]] += loc[np.uint64(j) * SWEEP_ROW + np.uint64(2)]


@njit(cache=True, nogil=True, inline="always")
def _gather_block(classes, values, loc, row):  # pragma: no cover - compiled
    """Row j of flat ``loc`` (``row`` entries): ``values[0][classes[j]], values[1][classes[j]], ...``, then
    zeros (the block's sums)."""
    n = len(values)
    for j in range(len(classes)):
        c = classes[j]
        base = np.uint64(j) * row
        for col in range(n):
            loc[base + np.uint64(col)] = values[col][c]
        for col in range(n, row):
            loc[base + np.uint64(col)] = 0.0


@njit(cache=True, nogil=True, inline="always")
def _sweep_seekers(off, cls, lam, loc, log_not_paired, s0, s1):  # pragma: no cover - compiled
    """Seekers ``s0..s1-1``, walked two at a time, interleaved: their running products are two
    independent multiplication chains, which the processor overlaps with the class lookups.  Pair
    positions are unsigned, so the compiled loop needs no negative-index check."""
    s = s0
    while s + 1 < s1:
        i, end_a = np.uint64(off[s]), np.uint64(off[s + 1])
        j, end_b = np.uint64(off[s + 1]), np.uint64(off[s + 2])
        n = min(end_a - i, end_b - j)
        weight_a, total_a, weight_b, total_b = lam[s], 0.0, lam[s + 1], 0.0
        for step in range(n):
            c = np.uint64(cls[i + step]) * SWEEP_ROW
            d = np.uint64(cls[j + step]) * SWEEP_ROW
            loc[c + np.uint64(2)] += weight_a
            weight_a *= loc[c]
            total_a += loc[c + _ONE]
            loc[d + np.uint64(2)] += weight_b
            weight_b *= loc[d]
            total_b += loc[d + _ONE]
        log_not_paired[s] = _walk(i + n, end_a, cls, weight_a, total_a, loc)  # the longer list's rest
        log_not_paired[s + 1] = _walk(j + n, end_b, cls, weight_b, total_b, loc)
        s += 2
    if s < s1:
        log_not_paired[s] = _walk(np.uint64(off[s]), np.uint64(off[s + 1]), cls, lam[s], 0.0, loc)


@njit(cache=True, nogil=True, inline="always")
def _walk(i, end, cls, weight, total, loc):  # pragma: no cover - compiled
    """One seeker's pairs ``i..end-1`` (unsigned) from running product ``weight`` and log sum ``total``;
    the final sum."""
    while i < end:
        c = np.uint64(cls[i]) * SWEEP_ROW
        loc[c + np.uint64(2)] += weight
        weight *= loc[c]
        total += loc[c + _ONE]
        i += _ONE
    return total


@njit(cache=True, nogil=True)
def savings_blocks(
    off,
    local,
    lam,
    q,
    log_q,
    one_minus_q,
    block_seeker,
    block_cls,
    block_cls_off,
    b0,
    b1,
    by_class,
    by_seeker,
    log_not_paired,
    loc,
    nodes,
    geometry,
    dist,
    cells,
    todo,
    to_o,
):  # pragma: no cover
    """:func:`sweep_blocks` that also sums the pair quantities of the savings pass (§2.7).

    Per class c: ``by_class[c, 0..3] += w · (1, E, shared, detour)`` (column 0
    is H_c); per seeker s: ``by_seeker[s, 0..3] += w (1 - Q_c) · (1, E, shared,
    detour)``, with ``w = λ_s Π_{c' ≻_s c} Q_c'`` (so ``w (1 - Q_c)`` is the
    pairing rate of s with class c, telescoped).  A pair's E, shared distance
    and seeker detour are derived from the geometry as in :func:`pair_values`
    (``geometry`` = seeker origin, seeker destination, l_B, class head, class
    l(h, d_A), class destination, D̄ + tolerance, keep E <= 0, min_feasible;
    ``dist`` the all-pairs matrix), bit for bit.

    Scratch: ``loc`` (flat, :data:`SAVINGS_ROW` per class) holds a block's
    ``Q``, ``log Q``, ``1 - Q``, its four class sums and the classes' ``a =
    l(h, o) - l(h, d_A)`` for the current origin o (recomputed when the origin
    changes: the seekers come sorted by origin) in one cache-line row per
    class, ``nodes`` the classes' destinations.  ``cells`` (one
    :data:`CELL_ROW` row per node) holds the current seeker's (d_A) cells
    (:func:`_fill_cell`), filled for the destinations its list names (listed
    in ``todo``) before its pairs are walked; ``to_o`` the column ``l(., o)``.
    """
    origin, dest, solo, class_head, class_rest, class_dest, d_lim, keep_nonpositive, min_feasible = geometry
    n_nodes = dist.shape[0]
    flat = cells.reshape(-1)  # a view: a node's row is a shift of its number
    for v in range(n_nodes):
        flat[np.uint64(v) * CELL_ROW + np.uint64(7)] = -1.0  # no seeker's cell
    for b in range(b0, b1):
        k0 = block_cls_off[b]
        k = block_cls_off[b + 1] - k0
        _gather_block(block_cls[k0 : k0 + k], (q, log_q, one_minus_q), loc, SAVINGS_ROW)
        for j in range(k):
            nodes[j] = class_dest[block_cls[k0 + j]]
        block_o = -1
        for s in range(block_seeker[b], block_seeker[b + 1]):
            o, d_b, l_b = origin[s], dest[s], solo[s]
            row_o, from_b = dist[o], dist[d_b]
            if o != block_o:  # a = l(h, o) - l(h, d_A) of the block's classes (the seekers come sorted by origin)
                for v in range(n_nodes):
                    to_o[v] = dist[v, o]
                for j in range(k):
                    c = block_cls[k0 + j]
                    loc[np.uint64(j) * SAVINGS_ROW + np.uint64(7)] = to_o[class_head[c]] - class_rest[c]
                block_o = o
            tag = float(s)
            i, end = np.uint64(off[s]), np.uint64(off[s + 1])
            m = 0
            while i < end:  # the seeker's destinations d_A, each once
                d_a = nodes[local[i]]
                r = np.uint64(d_a) * CELL_ROW
                if flat[r + np.uint64(7)] != tag:
                    flat[r + np.uint64(7)] = tag
                    todo[m] = d_a
                    m += 1
                i += _ONE
            for t in range(m):  # their cells: independent reads, which the processor overlaps
                d_a = todo[t]
                _fill_cell(
                    flat,
                    np.uint64(d_a) * CELL_ROW,
                    tag,
                    from_b[d_a],
                    dist[d_a, d_b],
                    row_o[d_a],
                    l_b,
                    d_lim,
                    keep_nonpositive,
                    min_feasible,
                )
            weight = lam[s]
            total = 0.0
            rate = rate_e = rate_sh = rate_det = 0.0
            i, end = np.uint64(off[s]), np.uint64(off[s + 1])
            while i < end:
                c = np.uint64(local[i]) * SAVINGS_ROW
                d_a = nodes[local[i]]
                r = np.uint64(d_a) * CELL_ROW
                a = loc[c + np.uint64(7)]
                # The order (0 FOFO, 1 FOLO) indexes the cell's values: no branch for the processor to mispredict.
                r += np.uint64(a <= flat[r])
                e = np.float64(np.float32(flat[r + _ONE] - a))
                sh = flat[r + np.uint64(3)]
                det = flat[r + np.uint64(5)]
                loc[c + np.uint64(3)] += weight
                loc[c + np.uint64(4)] += weight * e
                loc[c + np.uint64(5)] += weight * sh
                loc[c + np.uint64(6)] += weight * det
                pair = weight * loc[c + np.uint64(2)]
                rate += pair
                rate_e += pair * e
                rate_sh += pair * sh
                rate_det += pair * det
                weight *= loc[c]
                total += loc[c + _ONE]
                i += _ONE
            log_not_paired[s] = total
            by_seeker[s, 0] += rate
            by_seeker[s, 1] += rate_e
            by_seeker[s, 2] += rate_sh
            by_seeker[s, 3] += rate_det
        for j in range(k):
            c = block_cls[k0 + j]
            base = np.uint64(j) * SAVINGS_ROW
            for col in range(4):
                by_class[c, col] += loc[base + np.uint64(3 + col)]


@njit(cache=True, nogil=True, inline="always")
def _fill_cell(flat, r, tag, d_ba, d_ab, d_oa, l_b, d_lim, keep_nonpositive, min_feasible):  # pragma: no cover
    """Row ``r`` of the savings pass's cell table (:data:`CELL_ROW`): the cell's bound, then g, the shared
    distance and the seeker's detour (float32 values) for FOFO and FOLO, and ``tag`` (the seeker)."""
    bound, g_l, g_f = _cell(d_ba, d_ab, d_oa, l_b, d_lim, keep_nonpositive, min_feasible)
    flat[r], flat[r + _ONE], flat[r + np.uint64(2)] = bound, g_f, g_l
    flat[r + np.uint64(3)], flat[r + np.uint64(4)] = np.float32(d_oa), np.float32(l_b)
    flat[r + np.uint64(5)], flat[r + np.uint64(6)] = np.float32(-g_f), 0.0
    flat[r + np.uint64(7)] = tag


@njit(cache=True, nogil=True, inline="always")
def _cell(d_ba, d_ab, d_oa, l_b, d_lim, keep_nonpositive, min_feasible):  # pragma: no cover - compiled
    """``(bound, g_FOLO, g_FOFO)`` of a (seeker, d_A) cell of :func:`feasible_runs`: a stored pair of the cell
    lies in its FOLO run iff ``a <= bound`` (-inf when FOLO is not taken there), else in its FOFO run.

    ``d_ba = l(d_B, d_A)``, ``d_ab = l(d_A, d_B)``, ``d_oa = l(o_B, d_A)``, ``l_b
    = l_B``; the same float64 operations as :func:`feasible_runs`, so the
    bound and ``g`` are those the lists were built with.
    """
    f_ok = d_oa + d_ab - l_b <= d_lim
    g_f = l_b - d_oa - d_ab
    g_l = -d_ba
    thr_l = d_lim - l_b - d_ba
    if min_feasible:
        take_l = not f_ok or g_l > g_f
    else:
        take_l = not g_f >= g_l
    bound = -np.inf
    if take_l:
        bound = _minimum(thr_l, np.inf if keep_nonpositive else np.nextafter(g_l, -np.inf))
    return bound, g_l, g_f


@njit(cache=True, nogil=True)
def pair_values(off, cls, s0, s1, geometry, dist, saving, shared, detour):  # pragma: no cover - compiled
    """E, shared distance and seeker detour (float32) of the pairs of seekers ``s0..s1-1``.

    A pair of class c (head h, ``a = l(h, o_B) - l(h, d_A)``) lies in the FOLO
    or the FOFO run of its (seeker, d_A) cell (:func:`_cell`): FOLO gives ``E =
    g_FOLO - a``, shared ``l_B`` and no detour of the seeker; FOFO ``E = g_FOFO
    - a``, shared ``l(o_B, d_A)`` and detour ``-g_FOFO``, each rounded to
    float32 (§1.1; :func:`feasible_runs` for ``g``).  ``cls`` holds the pairs'
    global classes from pair ``off[s0]`` on; the outputs are written from index
    0.  ``geometry`` as in :func:`savings_blocks`.
    """
    origin, dest, solo, class_head, class_rest, class_dest, d_lim, keep_nonpositive, min_feasible = geometry
    base = off[s0]
    for s in range(s0, s1):
        o, d_b, l_b = origin[s], dest[s], solo[s]
        for i in range(off[s] - base, off[s + 1] - base):
            c = cls[i]
            d_a = class_dest[c]
            d_oa = dist[o, d_a]
            bound, g_l, g_f = _cell(dist[d_b, d_a], dist[d_a, d_b], d_oa, l_b, d_lim, keep_nonpositive, min_feasible)
            a = dist[class_head[c], o] - class_rest[c]
            if a <= bound:
                saving[i], shared[i], detour[i] = np.float32(g_l - a), np.float32(l_b), np.float32(0.0)
            else:
                saving[i], shared[i], detour[i] = np.float32(g_f - a), np.float32(d_oa), np.float32(-g_f)


@njit(cache=True, nogil=True)
def localize(
    lens, cls, limit, per_class, state, local_out, new_block_seeker, new_block_pos, block_cls_out
):  # pragma: no cover - compiled
    """Cut the seekers of ``lens`` (pairs ``cls``) into blocks of at most ``limit`` classes, continuing
    the open block of ``state`` = [block number, its class count, seekers so far, block classes so far,
    Σ class size over the pairs so far].

    A seeker starts a new block when its classes would overflow the open one
    (a seeker with more than ``limit`` classes gets a block of its own).
    Within a block classes are numbered in order of first use, written to
    ``local_out``; each block's classes are appended to ``block_cls_out``, and
    every new block's first seeker and first class position to
    ``new_block_seeker`` / ``new_block_pos``.  ``per_class[c]`` = (the block
    that last named c, c's number there, c's size) carries the open block's
    numbering between calls.  Returns (new blocks, block classes written).
    """
    block, width, seen, written, members = state[0], state[1], state[2], state[3], state[4]
    n_new = 0
    pos = 0
    i = 0
    for s in range(len(lens)):
        n = lens[s]
        if width > 0:
            fresh = 0
            for e in range(i, i + n):
                if per_class[cls[e], 0] != block:
                    fresh += 1
            if width + fresh > limit:
                block += 1
                width = 0
                new_block_seeker[n_new] = seen + s
                new_block_pos[n_new] = written + pos
                n_new += 1
        for e in range(i, i + n):
            c = cls[e]
            if per_class[c, 0] != block:
                per_class[c, 0] = block
                per_class[c, 1] = width
                block_cls_out[pos] = c
                pos += 1
                width += 1
            local_out[e] = per_class[c, 1]
            members += per_class[c, 2]
        i += n
    state[0], state[1], state[2], state[3], state[4] = block, width, seen + len(lens), written + pos, members
    return n_new, pos


@njit(cache=True, nogil=True)
def first_bad_block(off, local, block_seeker, block_cls_off, b0, b1):  # pragma: no cover - compiled
    """The first of blocks ``b0..b1-1`` one of whose pairs holds a local number outside its classes, or -1:
    the check that lets the sweeps index a block's table without bounds checks.  A min/max reduction per
    block (vectorised), one pass over the lists."""
    for b in range(b0, b1):
        width = block_cls_off[b + 1] - block_cls_off[b]
        i0, i1 = off[block_seeker[b]], off[block_seeker[b + 1]]
        if i1 <= i0:
            continue
        lo = hi = local[i0]
        for i in range(i0, i1):
            v = local[i]
            lo = min(lo, v)
            hi = max(hi, v)
        if np.int64(lo) < 0 or np.int64(hi) >= width:
            return b
    return -1


@njit(cache=True, nogil=True)
def count_at_most(a, lo, size, t):  # pragma: no cover - compiled
    """``(k, searched)``: k = how many of the ascending ``a[lo:lo + size]`` are ``<= t`` (size >= 1).

    A threshold at or above the largest value counts them all, one below the
    smallest (or NaN) counts none, and only the rest take a binary search
    (``searched`` = 1; an exact count: the values are compared, never rounded).
    """
    hi = lo + size
    if t >= a[hi - 1]:
        return size, 0
    if not t >= a[lo]:
        return 0, 0
    first = lo
    while lo < hi:  # first value > t
        mid = (lo + hi) >> 1
        if a[mid] <= t:
            lo = mid + 1
        else:
            hi = mid
    return lo - first, 1


@njit(cache=True, nogil=True, inline="always")
def _minimum(x, y):  # pragma: no cover - compiled
    """``np.minimum`` of two floats: NaN if either is NaN."""
    if x != x:
        return x
    if y != y:
        return y
    return x if x <= y else y


@njit(cache=True, nogil=True)
def feasible_runs(
    from_b,
    to_b,
    solo_b,
    group_dest,
    group_d_oa,
    a,
    start,
    size,
    d_lim,
    keep_nonpositive,
    min_feasible,
    row,
    first,
    length,
    piece_g,
    shared,
    detour,
):  # pragma: no cover - compiled
    """The pieces of one origin's seekers (``match_sets`` stage 2): ``(pieces written, searches)``.

    For seeker row r (solo length ``solo_b[r]``; ``from_b[r]`` and ``to_b[r]``
    are the distances from and to its destination d_B, rows of the all-pairs
    matrix and of its transpose) and destination group u (``group_dest[u]``,
    ``l(o, d_A) = group_d_oa[u]``, ascending ``a`` values
    ``a[start[u]:start[u] + size[u]]``)::

        FOFO feasible for B  <=>  l(o,d_A) + l(d_A,d_B) - l_B <= D̄
        E_FOFO = g_f - a,  g_f = l_B - l(o,d_A) - l(d_A,d_B)
        E_FOLO = g_l - a,  g_l = -l(d_B,d_A);   FOLO feasible <=> a <= D̄ - l_B - l(d_B,d_A)

    and E > 0 (unless ``keep_nonpositive``) <=> ``a <= nextafter(g, -inf)``.
    With ``min_feasible`` a class takes FOLO where FOLO is shorter (g_l >
    g_f) and feasible, FOFO otherwise; else the shorter order is chosen first
    and then tested.  Each (row, group, order) run ``[lo, hi)`` of the group
    is found by exact counts (:func:`count_at_most`).  The nonempty runs are
    written in row order, within a row the FOLO runs then the FOFO runs, each
    by ascending group: run start ``first`` (index into ``a``), ``length``, its
    ``g`` (float64) and the shared distance and B's detour on it (float32;
    FOLO: l_B and 0, FOFO: l(o,d_A) and -g_f).  Returns ``(-1, 0)`` when the
    outputs are too short (the caller retries with longer ones).
    """
    capacity = len(row)
    n_u = len(group_dest)
    fofo_u = np.empty(n_u, dtype=np.int64)  # a row's FOFO runs, written after its FOLO runs
    fofo_lo = np.empty(n_u, dtype=np.int64)
    fofo_hi = np.empty(n_u, dtype=np.int64)
    fofo_g = np.empty(n_u)
    k = 0
    searches = 0
    for r in range(len(solo_b)):
        l_b = solo_b[r]
        n_fofo = 0
        for u in range(n_u):
            d_a = group_dest[u]
            d_ba = from_b[r, d_a]
            d_ab = to_b[r, d_a]
            f_ok = group_d_oa[u] + d_ab - l_b <= d_lim
            g_f = l_b - group_d_oa[u] - d_ab
            g_l = -d_ba
            thr_l = d_lim - l_b - d_ba
            if min_feasible:
                folo_pref = g_l > g_f  # L_FOLO < L_FOFO (tie -> FOFO)
                take_l = not f_ok or folo_pref
                take_f = f_ok
            else:
                take_l = not g_f >= g_l
                take_f = not take_l and f_ok
                folo_pref = False
            if take_l:
                cut_l = np.inf if keep_nonpositive else np.nextafter(g_l, -np.inf)
                hi, s = count_at_most(a, start[u], size[u], _minimum(thr_l, cut_l))
                searches += s
                if hi > 0:
                    if k == capacity:
                        return -1, 0
                    row[k], first[k], length[k], piece_g[k] = r, start[u], hi, g_l
                    shared[k], detour[k] = np.float32(l_b), np.float32(0.0)
                    k += 1
            if take_f:
                lo = 0
                if folo_pref:  # FOLO's feasible classes are taken by FOLO
                    lo, s = count_at_most(a, start[u], size[u], thr_l)
                    searches += s
                cut_f = np.inf if keep_nonpositive else np.nextafter(g_f, -np.inf)
                hi, s = count_at_most(a, start[u], size[u], cut_f)
                searches += s
                if hi > lo:
                    fofo_u[n_fofo], fofo_lo[n_fofo], fofo_hi[n_fofo], fofo_g[n_fofo] = u, lo, hi, g_f
                    n_fofo += 1
        if k + n_fofo > capacity:
            return -1, 0
        for j in range(n_fofo):
            u = fofo_u[j]
            row[k], first[k], length[k], piece_g[k] = r, start[u] + fofo_lo[j], fofo_hi[j] - fofo_lo[j], fofo_g[j]
            shared[k], detour[k] = np.float32(group_d_oa[u]), np.float32(-fofo_g[j])
            k += 1
    return k, searches


@njit(cache=True, nogil=True)
def net_saving_keys(
    rows, start, n, piece_g, kappa, tie_rank, tie_bits, q_bits, grid, q_limit, keys
):  # pragma: no cover - compiled
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
def class_products(rho, members, class_off, class_log_q, member_log_r, c0, c1):  # pragma: no cover - compiled
    """Per class c in ``c0..c1-1``: ``log Q_c = Σ_{t∈c} log(1 - ρ_t)``; per member t: ``log r_t``, the same
    sum over the members before t (members in ``(w, k)`` order, ``members`` grouped by ``class_off``)."""
    for c in range(c0, c1):
        total = 0.0
        for i in range(class_off[c], class_off[c + 1]):
            t = members[i]
            member_log_r[t] = total
            total += np.log1p(-rho[t])
        class_log_q[c] = total


@njit(cache=True, nogil=True)
def taker_map(
    class_h,
    log_not_paired,
    member_log_r,
    cls,
    tau,
    od_state_off,
    rate,
    poisson,
    rho_cap,
    eta,
    p_taker,
    log_not_taker,
    lam_taker,
    rho_next,
    clipped,
    w0,
    w1,
):  # pragma: no cover - compiled
    """(A2), (A3), (A5), (A6) along the taker states of ODs ``w0..w1-1``, in one pass (see
    :func:`.fixed_point.evaluate`).

    ``η_t = r_t H_c``, ``x = η_t τ_t``, ``p_t = 1 - e^{-x}``; ``Σ_{j<k} x_j``
    along the path; ``λ_t = λ_w (1 - p_s) / Π_{j<k} (1 - p_j)`` in log space;
    ``ρ'_t = λ_t τ_t (1 - e^{-x}) / x`` (Little's law, A5; ``λ_t τ_t`` at x =
    0), or ``1 - e^{-that}`` when ``poisson``; clipped to ``[0, rho_cap]``.
    """
    for w in range(w0, w1):
        before = 0.0
        lam_w = rate[w]
        log_free = log_not_paired[w]
        for t in range(od_state_off[w], od_state_off[w + 1]):
            e = np.exp(member_log_r[t]) * class_h[cls[t]]
            x = e * tau[t]
            p = -np.expm1(-x)
            lam = lam_w * np.exp(log_free - before)
            g = p / x if x > 0 else 1.0
            load = lam * tau[t] * g
            raw = -np.expm1(-load) if poisson else load
            eta[t] = e
            p_taker[t] = p
            log_not_taker[t] = before
            lam_taker[t] = lam
            clipped[t] = raw > rho_cap
            rho_next[t] = min(max(raw, 0.0), rho_cap)
            before += x
