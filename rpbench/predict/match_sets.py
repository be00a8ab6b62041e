"""Matching sets T_s / S_t, pair savings E(s,t) and the priority order (ALGORITHMS.md §2.3-§2.4).

For every seeker ``s(w')`` (one per OD) this builds the list of taker
*classes* (see :mod:`.states`) it can pair with, sorted by priority.  A pair
is the POOL primitive of §1.1 with ``A`` = the taker at ``(h, δ, pre)`` and
``B`` = the seeker::

    p = l(h, o_B)                    pk = pre + p <= R̄
    FOFO: detour_A = p + l(o_B,d_A) - l(h,d_A)          detour_B = l(o_B,d_A) + l(d_A,d_B) - l_B
    FOLO: detour_A = p + l_B + l(d_B,d_A) - l(h,d_A)    detour_B = 0
    E = l(h,d_A) + l_B - L_chosen  (δ cancels: δ + l(h,d_A) = l_A)

The chosen order is the feasible one with the smaller L (tie FOFO), or
``order_rule="min_then_check"``.  Pairs with ``E <= 0`` are dropped unless
``keep_nonpositive`` (A11).  Thresholds are inclusive with the 1e-9 m
tolerance of :mod:`rpbench.geometry`.

**Vectorisation** (never a loop per pair).  Seekers are processed per
origin node ``o``:

1. *Spatial pruning* (independent of ``d_B``): the classes whose head lies
   within R̄ of ``o`` (one row of the distance matrix; classes are numbered
   by head node, so these are a few index ranges), with ``pk <= R̄``, FOFO's
   ``detour_A <= D̄`` (FOLO's is never smaller, by the triangle inequality)
   and, when E > 0 is required, ``p < l(h,d_A)`` (since ``E <= l(h,d_A) - p``).
2. The survivors are grouped by destination ``d_A`` and sorted by
   ``a = p - l(h,d_A)``.  For one seeker and one group, FOFO's feasibility
   for ``B``, both service-order lengths up to ``a`` and the order choice
   depend only on ``(d_A, d_B)``; FOLO is feasible iff ``a <= threshold`` and
   E > 0 iff ``a < g``.  A seeker's feasible pairs in a group are therefore
   at most two runs of the ``a``-sorted group, found by exact binary search
   on integer ranks.  The work is O(seekers x groups x log), not
   O(seekers x classes).
3. The runs are expanded, their priorities computed, and the seekers'
   lists sorted together with one ``np.sort`` of packed 64-bit keys
   ``(seeker, priority, tie rank, FOLO flag)``.

**Priority and ties** (§2.4, A7).  Default ``net_saving``: descending
``E - pk`` (the seed's myopic V1 utility, Eq. 7).  Priorities are compared on
a grid of 2^-20 m (about 1 µm): values closer than that are ties, broken by
ascending ``pk`` (same grid), then by class index (classes are numbered by
head node, entry link, destination), and within a class by ``(w, k)``.

**Storage.**  Seekers are stored in blocks of about 2^20 pairs (consecutive
ODs), so the lists are never copied into one huge array.  Per pair: the
class (int32), the saving ``E``, the shared distance and the seeker's detour
(float32: sub-millimetre rounding at urban distances; the fixed point only
uses the order of the classes).  The taker's detour is
``shared - E - detour_seeker`` and its ride from ``h`` is
``l(h,d_A) - E - detour_seeker + shared``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from rpbench.geometry import TOLERANCE_M
from rpbench.predict._arrays import expand_ranges, offsets_from_counts
from rpbench.predict.config import PredictConfig
from rpbench.predict.rates import OdRates
from rpbench.predict.states import StateSpace
from rpbench.scenarios.base import Params

GRID = float(1 << 20)          # priority / pick-up grid: 2^-20 m
Q_BITS = 39                    # quantised priorities cover (-2^18, 2^18) m
_Q_LIMIT = float(1 << 18) - 1.0
BLOCK_PAIRS = 1 << 20          # pairs per stored block
SORT_ENTRIES = 1 << 21         # entries expanded and sorted at once (bounds temporaries)


@dataclass(frozen=True, eq=False)
class Block:
    """The sorted lists of seekers ``s0..s1-1`` (local CSR offsets)."""

    s0: int
    s1: int
    off: np.ndarray               # int64 (s1-s0+1)
    cls: np.ndarray               # int32 taker class per pair
    saving_m: np.ndarray          # float32 E(s, t)
    shared_m: np.ndarray          # float32 shared distance
    seeker_detour_m: np.ndarray   # float32 detour of the seeker

    @property
    def nbytes(self) -> int:
        return int(self.off.nbytes + self.cls.nbytes + self.saving_m.nbytes + self.shared_m.nbytes
                   + self.seeker_detour_m.nbytes)


@dataclass(frozen=True, eq=False)
class Matching:
    """Each seeker's taker classes in priority order; blocks partition the ODs in order."""

    seeker_off: np.ndarray        # int64 (W+1): global offsets (pairs of s(w) are [off[w], off[w+1]))
    blocks: tuple[Block, ...]
    stats: dict = field(default_factory=dict)

    @property
    def n_pairs(self) -> int:
        """Stored (seeker, class) pairs."""
        return int(self.seeker_off[-1])

    def n_state_pairs(self, space: StateSpace) -> int:
        """Seeker-taker-state pairs of the model (Σ_s |T_s|)."""
        size = space.class_size
        return int(sum(size[b.cls].sum() for b in self.blocks))

    @property
    def nbytes(self) -> int:
        return int(self.seeker_off.nbytes + sum(b.nbytes for b in self.blocks))

    def seeker(self, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(classes, E, shared, seeker detour) of seeker ``s(w)``, in priority order (views)."""
        starts = np.fromiter((b.s0 for b in self.blocks), dtype=np.int64, count=len(self.blocks))
        b = self.blocks[int(np.searchsorted(starts, w, side="right")) - 1]
        i0, i1 = b.off[w - b.s0], b.off[w - b.s0 + 1]
        return b.cls[i0:i1], b.saving_m[i0:i1], b.shared_m[i0:i1], b.seeker_detour_m[i0:i1]

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All pairs concatenated in OD order (for tests and small models)."""
        if not self.blocks:
            z = np.zeros(0, dtype=np.float32)
            return np.zeros(0, dtype=np.int32), z, z, z
        return tuple(np.concatenate([getattr(b, f) for b in self.blocks])
                     for f in ("cls", "saving_m", "shared_m", "seeker_detour_m"))


def build_matching(space: StateSpace, rates: OdRates, dist: np.ndarray, params: Params,
                   config: PredictConfig) -> Matching:
    """Matching sets of every seeker (see the module docstring for the method)."""
    t0 = time.perf_counter()
    writer = _BlockWriter(len(rates))
    origin = rates.origin
    if len(origin):
        builder = _Builder(space, rates, dist, params, config)
        bounds = np.flatnonzero(np.diff(origin)) + 1
        starts = np.concatenate([[0], bounds]).astype(np.int64)
        ends = np.concatenate([bounds, [len(origin)]]).astype(np.int64)
        for w0, w1 in zip(starts, ends):
            builder.origin_block(int(origin[w0]), int(w0), int(w1), writer)
        stats = builder.stats
    else:
        stats = {}
    blocks = writer.finish()
    lens = np.concatenate([np.diff(b.off) for b in blocks]) if blocks else np.zeros(0, dtype=np.int64)
    return Matching(seeker_off=offsets_from_counts(lens), blocks=tuple(blocks),
                    stats=dict(stats, build_s=time.perf_counter() - t0))


class _BlockWriter:
    """Collects per-seeker lists in OD order into preallocated blocks of about BLOCK_PAIRS pairs.

    Sorted entries are written straight into the block's buffers (no
    concatenation copy); a block keeps views of its filled part.
    """

    def __init__(self, n_od: int) -> None:
        self.n_od = n_od
        self.blocks: list[Block] = []
        self.start = 0           # first seeker of the pending block
        self.next = 0            # next seeker expected
        self.lens: list[np.ndarray] = []
        self.buf: tuple[np.ndarray, ...] | None = None
        self.fill = 0

    def reserve(self, n: int) -> tuple[np.ndarray, ...]:
        """Views for the next ``n`` pairs: (class int32, saving, shared, seeker detour float32)."""
        if self.buf is None or self.fill + n > len(self.buf[0]):
            if self.fill:
                self._flush()
            cap = max(BLOCK_PAIRS + SORT_ENTRIES, n)
            self.buf = (np.empty(cap, dtype=np.int32), np.empty(cap, dtype=np.float32),
                        np.empty(cap, dtype=np.float32), np.empty(cap, dtype=np.float32))
        return tuple(b[self.fill:self.fill + n] for b in self.buf)

    def commit(self, w0: int, lens: np.ndarray, n: int = 0) -> None:
        """Seekers ``w0 .. w0+len(lens)-1`` with ``lens`` pairs each (``n`` = their sum, just reserved)."""
        assert w0 == self.next, "seekers must be committed in OD order"
        self.lens.append(np.asarray(lens, dtype=np.int64))
        self.next = w0 + len(lens)
        self.fill += n
        if self.fill >= BLOCK_PAIRS:
            self._flush()

    def _flush(self) -> None:
        if self.next == self.start:
            return
        lens = np.concatenate(self.lens)
        if self.buf is None:
            self.buf = (np.zeros(0, dtype=np.int32),) + tuple(np.zeros(0, dtype=np.float32) for _ in range(3))
        for b in self.buf:          # give back the unused tail (realloc shrinks in place; no views remain)
            b.resize(self.fill, refcheck=False)
        self.blocks.append(Block(self.start, self.next, offsets_from_counts(lens), *self.buf))
        self.start, self.lens, self.buf, self.fill = self.next, [], None, 0

    def finish(self) -> list[Block]:
        if self.next < self.n_od:
            self.commit(self.next, np.zeros(self.n_od - self.next, dtype=np.int64))
        self._flush()
        return self.blocks


class _Builder:
    """Per-origin construction of the sorted matching lists."""

    def __init__(self, space: StateSpace, rates: OdRates, dist: np.ndarray, params: Params,
                 config: PredictConfig) -> None:
        self.space, self.config = space, config
        self.dist = dist
        self.r_lim = params.max_pickup_m + TOLERANCE_M
        self.d_lim = params.max_detour_m + TOLERANCE_M
        self.dest = rates.destination.astype(np.int64)
        self.solo = space.solo_m
        if np.any(np.diff(space.class_head) < 0):
            raise ValueError("taker classes must be numbered by head node")
        self.head_off = offsets_from_counts(np.bincount(space.class_head, minlength=dist.shape[0]))
        self.stats = {"stage1_candidates": 0, "stage1_kept": 0, "group_queries": 0}

    # ------------------------------------------------------------------ stage 1
    def origin_block(self, o: int, w0: int, w1: int, writer: _BlockWriter) -> None:
        """Sorted lists of the seekers ``w0..w1-1`` (all with origin ``o``), handed to ``writer``."""
        sp, cfg = self.space, self.config
        to_o = np.ascontiguousarray(self.dist[:, o])                          # l(h, o) for every node h
        near = np.flatnonzero(to_o <= self.r_lim)                            # within R̄ of the seekers
        cand = expand_ranges(self.head_off[near], self.head_off[near + 1])   # sorted by class index
        self.stats["stage1_candidates"] += len(cand)
        row_o = self.dist[o]
        p = to_o[sp.class_head[cand]]
        pk = sp.class_pre_m[cand] + p
        rest = sp.class_rest_m[cand]
        d_a = sp.class_dest[cand]
        a = p - rest
        keep = (pk <= self.r_lim) & (a + row_o[d_a] <= self.d_lim)         # pick-up; FOFO detour of A
        if not cfg.keep_nonpositive:
            keep &= a < 0                                                   # E <= l(h,d_A) - p
        if not keep.any():
            writer.commit(w0, np.zeros(w1 - w0, dtype=np.int64))
            return
        g = _Group(cand[keep], a[keep], pk[keep], rest[keep], d_a[keep], row_o)
        self.stats["stage1_kept"] += g.n
        pieces = self._pieces(g, w0, w1)
        self._emit(g, w0, w1, pieces, writer)

    # ------------------------------------------------------------------ stage 2
    def _pieces(self, g: "_Group", w0: int, w1: int) -> "_Pieces":
        """Runs of feasible classes per (seeker, d_A group), grouped by seeker."""
        cfg = self.config
        d_b = self.dest[w0:w1]
        l_b = self.solo[w0:w1][:, None]
        d_ba = self.dist[np.ix_(d_b, g.dest)]                    # l(d_B, d_A)   (m x U)
        d_ab = self.dist[np.ix_(g.dest, d_b)].T                  # l(d_A, d_B)
        f_ok = (g.d_oa + d_ab - l_b <= self.d_lim).ravel()       # FOFO detour of B
        g_f = (l_b - g.d_oa - d_ab).ravel()                      # E_FOFO = g_f - a
        g_l = (-d_ba).ravel()                                    # E_FOLO = g_l - a
        thr_l = (self.d_lim - l_b - d_ba).ravel()                # FOLO feasible <=> a <= thr_l
        if cfg.keep_nonpositive:
            cut_f = cut_l = np.full(len(g_f), np.inf)
        else:                                                    # E > 0 <=> a < g <=> a <= nextafter(g, -inf)
            cut_f, cut_l = np.nextafter(g_f, -np.inf), np.nextafter(g_l, -np.inf)
        m, n_u = len(d_b), len(g.dest)
        us = np.tile(np.arange(n_u, dtype=np.int64), m)
        if cfg.order_rule == "min_feasible":
            folo_pref = g_l > g_f                                # L_FOLO < L_FOFO (tie -> FOFO)
            sel_l = np.flatnonzero(~f_ok | folo_pref)
            sel_f = np.flatnonzero(f_ok)
            # Where FOLO is preferred, its feasible classes (a <= thr_l) take FOLO; FOFO gets the rest.
            lo_f = np.zeros(len(sel_f), dtype=np.int64)
            both = sel_f[folo_pref[sel_f]]
            lo_f[folo_pref[sel_f]] = g.count(us[both], thr_l[both])
        else:                                                    # min_then_check: order first, then test it
            fofo_first = g_f >= g_l
            sel_l = np.flatnonzero(~fofo_first)
            sel_f = np.flatnonzero(fofo_first & f_ok)
            lo_f = np.zeros(len(sel_f), dtype=np.int64)
        hi_l = g.count(us[sel_l], np.minimum(thr_l[sel_l], cut_l[sel_l]))
        hi_f = g.count(us[sel_f], cut_f[sel_f])
        self.stats["group_queries"] += g.queries
        g.queries = 0
        pieces = _Pieces(
            flat=np.concatenate([sel_l, sel_f]),
            lo=np.concatenate([np.zeros(len(sel_l), dtype=np.int64), lo_f]),
            hi=np.concatenate([hi_l, hi_f]),
            folo=np.concatenate([np.ones(len(sel_l), dtype=np.int64), np.zeros(len(sel_f), dtype=np.int64)]),
            n_u=n_u, g_f=g_f, g_l=g_l)
        return pieces.nonempty(g, self.solo[w0:w1])

    def _emit(self, g: "_Group", w0: int, w1: int, pc: "_Pieces", writer: _BlockWriter) -> None:
        """Expand, prioritise and sort the pieces, a bounded number of entries at a time."""
        m = w1 - w0
        per_row = np.bincount(pc.row, weights=pc.n, minlength=m).astype(np.int64)
        cum = np.cumsum(per_row)
        r0 = 0
        while r0 < m:
            base = cum[r0 - 1] if r0 else 0
            r1 = int(np.searchsorted(cum, base + SORT_ENTRIES, side="right"))
            r1 = min(m, max(r1, r0 + 1), r0 + g.rows_per_sort)
            i0, i1 = (int(i) for i in np.searchsorted(pc.row, [r0, r1]))
            total = int(cum[r1 - 1] - base)
            if total:
                self._sorted_entries(g, pc, i0, i1, r0, w0, writer.reserve(total))
            writer.commit(w0 + r0, per_row[r0:r1], total)
            r0 = r1

    def _sorted_entries(self, g: "_Group", pc: "_Pieces", i0: int, i1: int, r0: int, w0: int, out) -> None:
        """Pieces ``i0..i1-1`` (seeker rows from ``r0``) expanded, sorted and written into ``out``."""
        n = pc.n[i0:i1]
        piece = np.repeat(np.arange(i0, i1), n)
        col = expand_ranges(pc.start[i0:i1], pc.start[i0:i1] + n)
        if self.config.priority == "net_saving":
            prio = np.repeat(pc.g[i0:i1], n)
            prio += g.kappa[col]                               # E - pk = g - a - pk
        else:
            e = pc.g[piece] - g.a[col]
            prio = _priority(self.config.priority, e, g.pk[col], pc.shared[piece], pc.det[piece],
                             g.rest[col], self.solo[w0 + pc.row[piece]])
        perm = _priority_order(pc.row[i0:i1] - r0, n, prio, g.tie_rank[col], g.tie_bits)
        col = col[perm]
        piece = piece[perm]
        cls, saving, shared, detour = out
        np.take(g.cls, col, out=cls)
        np.subtract(pc.g[piece], g.a[col], out=saving, casting="same_kind")
        np.take(pc.shared, piece, out=shared)
        np.take(pc.det, piece, out=detour)


@dataclass(eq=False)
class _Pieces:
    """Runs ``[start, start + n)`` of survivors, one per (seeker row, group, service order)."""

    flat: np.ndarray     # row * n_u + group
    lo: np.ndarray       # run start within the group
    hi: np.ndarray       # run end within the group
    folo: np.ndarray     # 1 = FOLO, 0 = FOFO
    n_u: int
    g_f: np.ndarray      # per (row, group): E_FOFO + a
    g_l: np.ndarray      # per (row, group): E_FOLO + a
    row: np.ndarray = None       # seeker row of each run (runs sorted by row)
    start: np.ndarray = None     # first survivor of the run
    n: np.ndarray = None         # run length
    g: np.ndarray = None         # E + a on the run (float64)
    shared: np.ndarray = None    # shared distance on the run (float32)
    det: np.ndarray = None       # seeker detour on the run (float32)

    def nonempty(self, grp: "_Group", solo: np.ndarray) -> "_Pieces":
        keep = np.flatnonzero(self.hi > self.lo)
        flat, folo = self.flat[keep], self.folo[keep]
        row = flat // self.n_u
        # Group the runs by seeker row (radix sort on small ints is linear).
        order = np.argsort(row.astype(np.int32 if row.size and row.max() > 32767 else np.int16), kind="stable")
        keep, flat, folo, row = keep[order], flat[order], folo[order], row[order]
        self.flat, self.folo, self.row = flat, folo, row
        u = flat % self.n_u
        self.start = grp.start[u] + self.lo[keep]
        self.n = self.hi[keep] - self.lo[keep]
        is_folo = folo.astype(bool)
        g_f = self.g_f[flat]
        self.g = np.where(is_folo, self.g_l[flat], g_f)
        # FOLO: B rides alone to d_B, shared = l_B, detour_B = 0; FOFO: shared = l(o,d_A), detour_B = -g_f.
        self.shared = np.where(is_folo, solo[row], grp.d_oa[u]).astype(np.float32)
        self.det = np.where(is_folo, 0.0, -g_f).astype(np.float32)
        return self


class _Group:
    """Stage-1 survivors of one origin, sorted by (d_A, a), with exact per-group counting."""

    def __init__(self, cls, a, pk, rest, dest, row_o):
        n = len(a)
        by_a = np.argsort(a)                                 # one quicksort serves order and ranks
        sorted_a = a[by_a]
        # Left rank of each value (ties share the rank of their first occurrence).
        run_start = np.ones(n, dtype=bool)
        run_start[1:] = sorted_a[1:] != sorted_a[:-1]
        left = np.flatnonzero(run_start)[np.cumsum(run_start) - 1]
        rank = np.empty(n, dtype=np.int64)
        rank[by_a] = left
        # Exact (d_A, a) order: a stable radix pass on the destination over the a-sorted order.
        dkey = dest[by_a]
        order = by_a[np.argsort(dkey.astype(np.uint16) if dkey.max() < 65536 else dkey, kind="stable")]
        self.n = n
        self.cls = cls[order].astype(np.int32)
        self.a, self.pk, self.rest = a[order], pk[order], rest[order]
        dest = dest[order]
        self.kappa = -self.a - self.pk                       # E - pk = g + kappa
        new = np.ones(n, dtype=bool)
        new[1:] = dest[1:] != dest[:-1]
        self.start = np.flatnonzero(new).astype(np.int64)
        self.size = np.diff(np.append(self.start, n))
        self.dest = dest[self.start].astype(np.int64)
        self.u_of = np.cumsum(new) - 1
        self.d_oa = row_o[self.dest]                         # l(o, d_A) per group
        self.a_min = self.a[self.start]
        self.a_max = self.a[self.start + self.size - 1]
        # Integer ranks make (group, a) one exactly comparable int64 key.
        self.sorted_a = sorted_a
        self.stride = n + 1
        self.key = self.u_of * self.stride + rank[order]
        # Tie ranks: ascending pk on the priority grid, then class index (the survivors arrive in class
        # order, so the pre-sort position breaks ties).
        pk_q = np.floor(pk * GRID).astype(np.int64)
        if n < (1 << 25) and pk_q.max() < (1 << 38):
            tie = np.argsort((pk_q[order] << 25) | order)
        else:
            tie = np.lexsort((order, pk_q[order]))
        self.tie_rank = np.empty(n, dtype=np.int64)
        self.tie_rank[tie] = np.arange(n)
        self.tie_bits = max(1, int(n).bit_length())
        row_bits = 64 - Q_BITS - self.tie_bits
        self.rows_per_sort = 1 << row_bits if row_bits >= 1 else 1   # 1: _priority_order uses lexsort
        self.queries = 0

    def count(self, u: np.ndarray, threshold: np.ndarray) -> np.ndarray:
        """Number of classes of group ``u`` with ``a <= threshold`` (vectorised, exact)."""
        out = np.where(threshold >= self.a_max[u], self.size[u], 0)
        mid = np.flatnonzero((threshold >= self.a_min[u]) & (threshold < self.a_max[u]))
        if len(mid):
            um = u[mid]
            r = np.searchsorted(self.sorted_a, threshold[mid], side="right")
            out[mid] = np.searchsorted(self.key, um * self.stride + r, side="left") - self.start[um]
            self.queries += len(mid)
        return out


def _priority(kind: str, e, pk, shared, seeker_detour, rest, l_b) -> np.ndarray:
    """Priority value of each entry, larger = served first (§2.4)."""
    if kind == "net_saving":
        return e - pk
    if kind == "fl_utility":                     # e²/(e+pk), the FL V1 utility (Eq. 15) without α^k;
        with np.errstate(divide="ignore", invalid="ignore"):     # e <= 0 (kept on request): e, continuous at 0
            return np.where(e > 0, e * e / (e + pk), e)
    if kind == "pickup":                         # nearest first (the TR-B simulators)
        return -pk
    if kind == "vehicle_distance":               # ascending distance the vehicle drives from h
        return -(rest + l_b - e)
    # authors_feng_grid: -0.5 detour - 0.3 pickup + 0.2 shared (detour = both passengers')
    taker_detour = shared - e - seeker_detour
    return -0.5 * (seeker_detour + taker_detour) - 0.3 * pk + 0.2 * shared


def _priority_order(piece_row, piece_len, prio, tie_rank, tie_bits: int) -> np.ndarray:
    """Permutation sorting entries by (row, descending priority on the 2^-20 m grid, tie rank).

    Entries come in runs (pieces) of one seeker row each.  The three keys
    are packed into one uint64 (row | quantised priority | tie rank); keys
    are unique, so the unstable quicksort is deterministic.
    """
    row_bits = 64 - Q_BITS - tie_bits
    if row_bits >= 1 and int(piece_row.max()).bit_length() <= row_bits and np.abs(prio).max() < _Q_LIMIT:
        desc = np.multiply(prio, -GRID)
        desc += float(1 << (Q_BITS - 1))                    # in (0, 2^Q_BITS): larger priority, smaller key
        key = desc.astype(np.uint64)                        # positive: truncation is the floor
        key <<= np.uint64(tie_bits)
        key |= tie_rank.astype(np.uint64)
        key |= np.repeat(piece_row.astype(np.uint64) << np.uint64(Q_BITS + tie_bits), piece_len)
        return np.argsort(key)
    # Huge distances (beyond 2^18 m) or huge groups: the same order through a slower lexsort.
    row = np.repeat(piece_row, piece_len)
    return np.lexsort((tie_rank, np.floor(np.multiply(prio, -GRID)), row))
