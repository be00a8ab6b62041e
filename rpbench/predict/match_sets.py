"""Matching sets T_s / S_t, pair savings E(s,t) and the priority order (docs/algorithms.md §2.3-§2.4).

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

**Vectorisation** (never a loop per pair in Python).  Seekers are processed per
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
   (the values are compared, never rounded) in one compiled pass over the
   (seeker, group) cells, :func:`.kernels.feasible_runs`.  The work is
   O(seekers x groups x log), not O(seekers x classes).
3. The runs are expanded, their priorities computed, and the seekers'
   lists sorted together with one ``np.sort`` of packed 64-bit keys
   ``(seeker, priority, tie rank)``.

**Priority and ties** (§2.4, A7).  Default ``net_saving``: descending
``E - pk`` (the seed's myopic V1 utility, Eq. 7).  Priorities are compared on
a grid of 2^-20 m (about 1 µm): values closer than that are ties, broken by
ascending ``pk`` (same grid), then by class index (classes are numbered by
head node, entry link, destination), and within a class by ``(w, k)``.

**Storage.**  A pair stores its class only, as a block-local number (uint16,
see :mod:`.blocks`): two bytes a pair, appended origin by origin to one raw
file (see :mod:`.list_cache`, which keeps it in the cache) and read back as a
read-only memory map.  The rest of a pair is a function of its seeker, its
class and the distance matrix, recomputed where it is needed (the savings
pass, :func:`.kernels.pair_values`) with the float64 operations that built
the lists: the saving ``E = g - a`` rounded to float32, the shared distance
and the seeker's detour (float32), so the values are those of the lists'
construction, bit for bit, and need not be stored (six more bytes a pair,
1.7 GB on the month table).  The taker's
detour is ``shared - E - detour_seeker`` and its ride from ``h`` is
``l(h,d_A) - E - detour_seeker + shared``.

**Speed.**  Origins are independent and run in a few threads.  Sorting
(step 3) sorts the packed keys themselves, not an index: a key is unique and
its tie rank names the class survivor, so the sorted keys are the classes.
"""

from __future__ import annotations

import mmap
import sys
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import get_num_threads
from tqdm import tqdm

from rpbench.geometry import TOLERANCE_M
from rpbench.predict import kernels
from rpbench.predict._arrays import expand_ranges, offsets_from_counts
from rpbench.predict.blocks import BLOCK_CLASSES, ClassBlocks, Localizer, localize_lists
from rpbench.predict.config import PredictConfig
from rpbench.predict.rates import OdRates
from rpbench.predict.states import StateSpace
from rpbench.scenarios.base import Params

GRID = float(1 << 20)  # priority / pick-up grid: 2^-20 m
Q_BITS = 39  # quantised priorities cover (-2^18, 2^18) m
_Q_LIMIT = float(1 << 18) - 1.0
SORT_ENTRIES = 1 << 21  # entries expanded and sorted at once (bounds temporaries)
CHUNK_PAIRS = 1 << 24  # pairs per chunk when the sweeps stream the lists
SIZE_SAMPLES = 64  # seekers whose lists estimate the size of a build before it starts (about 10 %)


@dataclass(frozen=True, eq=False)
class ListGeometry:
    """What a pair's E, shared distance and seeker detour are computed from (see :func:`.kernels.pair_values`).

    Per seeker (OD) its origin, destination and ``l_B``; per taker class its
    head ``h``, ``l(h, d_A)`` and destination ``d_A``; D̄ with the tolerance,
    the E <= 0 and order rules of the lists, and the all-pairs distance matrix
    (read when first needed: a sweep of the fixed point does not).
    """

    origin: np.ndarray  # int64 per seeker
    destination: np.ndarray  # int64 per seeker
    solo_m: np.ndarray  # float64 per seeker: l_B
    class_head: np.ndarray  # int64 per class
    class_rest_m: np.ndarray  # float64 per class: l(h, d_A)
    class_dest: np.ndarray  # int64 per class
    d_lim: float  # D̄ + TOLERANCE_M
    keep_nonpositive: bool
    min_feasible: bool  # order_rule == "min_feasible"
    distances: Callable[[], np.ndarray] = field(repr=False)  # the all-pairs matrix (C order)

    @classmethod
    def of(
        cls,
        space: StateSpace,
        rates: OdRates,
        params: Params,
        config: PredictConfig,
        distances: Callable[[], np.ndarray],
    ) -> ListGeometry:
        return cls(
            origin=rates.origin.astype(np.int64),
            destination=rates.destination.astype(np.int64),
            solo_m=np.asarray(space.solo_m, dtype=np.float64),
            class_head=space.class_head.astype(np.int64),
            class_rest_m=np.asarray(space.class_rest_m, dtype=np.float64),
            class_dest=space.class_dest.astype(np.int64),
            d_lim=float(params.max_detour_m + TOLERANCE_M),
            keep_nonpositive=bool(config.keep_nonpositive),
            min_feasible=config.order_rule == "min_feasible",
            distances=distances,
        )

    def kernel_args(self) -> tuple:
        """The tuple the compiled kernels take."""
        return (
            self.origin,
            self.destination,
            self.solo_m,
            self.class_head,
            self.class_rest_m,
            self.class_dest,
            self.d_lim,
            self.keep_nonpositive,
            self.min_feasible,
        )

    def values(self, off: np.ndarray, cls: np.ndarray, s0: int, s1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(E, shared, seeker detour), float32, of the pairs of seekers ``s0..s1-1`` with global classes ``cls``."""
        n = len(cls)
        saving, shared, detour = (np.empty(n, dtype=np.float32) for _ in range(3))
        if n:
            dist = np.ascontiguousarray(self.distances())
            kernels.pair_values(
                off, np.ascontiguousarray(cls), s0, s1, self.kernel_args(), dist, saving, shared, detour
            )
        return saving, shared, detour


@dataclass(frozen=True, eq=False)
class Matching:
    """Each seeker's taker classes in priority order, as flat CSR arrays (the classes usually a memory map).

    The pairs of seeker ``s(w)`` are ``[seeker_off[w], seeker_off[w+1])`` of
    :attr:`local`, a read-only map of a file of the cache entry (see
    :mod:`.list_cache`): several processes share one copy in the page cache,
    and a sweep only brings in what it touches.  A pair's distances come from
    :attr:`geometry`.
    """

    seeker_off: np.ndarray  # int64 (W+1)
    local: np.ndarray  # uint16 (or int32) taker class per pair, numbered within its block
    blocks: ClassBlocks  # the seekers' blocks and the global class of each local number
    geometry: ListGeometry
    stats: dict = field(default_factory=dict)

    @classmethod
    def from_lists(
        cls, seeker_off, classes, geometry: ListGeometry, *, n_classes: int | None = None, limit: int = BLOCK_CLASSES
    ) -> Matching:
        """A matching held in memory, from global class lists (tests and small models)."""
        seeker_off = np.asarray(seeker_off, dtype=np.int64)
        classes = np.asarray(classes, dtype=np.int32)
        if n_classes is None:
            n_classes = int(classes.max()) + 1 if len(classes) else 0
        local, blocks = localize_lists(seeker_off, classes, n_classes, limit)
        return cls(seeker_off=seeker_off, local=local, blocks=blocks, geometry=geometry)

    @property
    def cls(self) -> np.ndarray:
        """The taker class of every pair (int32, computed in memory: for tests and small models)."""
        return self.blocks.classes(self.local, self.seeker_off, 0, len(self.seeker_off) - 1)

    @property
    def saving_m(self) -> np.ndarray:
        """E of every pair (float32, computed in memory: tests and small models)."""
        return self.arrays()[1]

    @property
    def shared_m(self) -> np.ndarray:
        """The shared distance of every pair (float32, computed in memory: tests and small models)."""
        return self.arrays()[2]

    @property
    def seeker_detour_m(self) -> np.ndarray:
        """The seeker's detour of every pair (float32, computed in memory: tests and small models)."""
        return self.arrays()[3]

    @property
    def n_pairs(self) -> int:
        """Stored (seeker, class) pairs."""
        return int(self.seeker_off[-1])

    def n_state_pairs(self, space: StateSpace) -> int:
        """Seeker-taker-state pairs of the model (Σ_s |T_s|): recorded when the lists were built."""
        if "state_pairs" in self.stats:
            return int(self.stats["state_pairs"])
        return self.count_state_pairs(space.class_size)

    def count_state_pairs(self, class_size: np.ndarray) -> int:
        """Σ_s |T_s| counted block by block: how often each local class is listed, times its size."""
        total, b = 0, self.blocks
        for k in range(b.n_blocks):
            i0, i1 = self.seeker_off[b.seeker_off[k]], self.seeker_off[b.seeker_off[k + 1]]
            table = b.cls[b.cls_off[k] : b.cls_off[k + 1]]
            listed = np.bincount(self.local[i0:i1], minlength=len(table))
            total += int(listed @ class_size[table])
        return total

    @property
    def nbytes(self) -> int:
        """Bytes of the lists (offsets, local classes, blocks)."""
        b = self.blocks
        return int(self.seeker_off.nbytes + self.local.nbytes + b.seeker_off.nbytes + b.cls.nbytes + b.cls_off.nbytes)

    def chunks(self, max_pairs: int = CHUNK_PAIRS):
        """``(s0, s1, i0, i1)``: seeker ranges of about ``max_pairs`` pairs (at least one seeker each)."""
        off, n_od = self.seeker_off, len(self.seeker_off) - 1
        s0 = 0
        while s0 < n_od:
            s1 = int(np.searchsorted(off, off[s0] + max_pairs, side="right")) - 1
            s1 = min(n_od, max(s1, s0 + 1))
            yield s0, s1, int(off[s0]), int(off[s1])
            s0 = s1

    def release_seekers(self, s0: int, s1: int) -> None:
        """Give back this process's pages of the pairs of seekers ``s0..s1-1``.

        The data stays in the page cache (a later read maps it again), but a
        pass over the whole list file no longer leaves it all resident.  A
        list that is not a memory map is left alone.
        """
        col = self.local
        mapped = getattr(col, "_mmap", None)  # numpy keeps the mmap object of a np.memmap here
        if mapped is None or not hasattr(mapped, "madvise"):
            return
        i0, i1 = int(self.seeker_off[s0]), int(self.seeker_off[s1])
        start = i0 * col.itemsize // mmap.PAGESIZE * mmap.PAGESIZE  # the file is mapped from byte 0
        end = min(i1 * col.itemsize, len(mapped))
        if end > start:
            mapped.madvise(mmap.MADV_DONTNEED, start, end - start)

    def seeker(self, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(classes, E, shared, seeker detour) of seeker ``s(w)``, in priority order."""
        classes = self.blocks.classes(self.local, self.seeker_off, w, w + 1)
        return (classes, *self.geometry.values(self.seeker_off, classes, w, w + 1))

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All pairs in OD order as in-memory arrays: classes, E, shared, seeker detour (tests, small models)."""
        classes = self.cls
        return (classes, *self.geometry.values(self.seeker_off, classes, 0, len(self.seeker_off) - 1))

    @classmethod
    def open(
        cls,
        directory: Path,
        seeker_off: np.ndarray,
        stats: dict,
        local_dtype: str,
        geometry: ListGeometry,
        *,
        n_classes: int | None = None,
    ) -> Matching:
        """The matching whose lists lie in ``directory`` (a read-only memory map); ``local_dtype`` names the
        dtype of the local class numbers.  With ``n_classes`` (a cache entry, not a fresh build) every
        class and local number is checked to be in range (``seeker_off`` must be checked by the caller)."""
        n, n_od = int(seeker_off[-1]), len(seeker_off) - 1
        if np.dtype(local_dtype) not in (np.dtype("<u2"), np.dtype("<i4")):
            raise ValueError(f"local class numbers of type {local_dtype!r} are not supported")
        local = _open_column(directory / "local.bin", local_dtype, n)
        blocks = ClassBlocks.load(directory, n_od, n_classes)
        if n_classes is not None:
            problem = blocks.local_problem(local, seeker_off)
            if problem is not None:
                raise ValueError(f"local.bin is inconsistent: {problem}")
        return cls(seeker_off=seeker_off, local=local, blocks=blocks, geometry=geometry, stats=stats)


def _open_column(path: Path, dtype: str, n: int) -> np.ndarray:
    if path.stat().st_size != n * np.dtype(dtype).itemsize:
        raise ValueError(f"{path.name} holds {path.stat().st_size} bytes, expected {n} {dtype} values")
    if n == 0:  # an empty file cannot be mapped
        return np.zeros(0, dtype=dtype)
    return np.memmap(path, dtype=dtype, mode="r", shape=(n,))


def build_matching(
    space: StateSpace,
    rates: OdRates,
    dist: np.ndarray,
    params: Params,
    config: PredictConfig,
    directory: Path,
    estimate: Callable[[int, int], None] | None = None,
) -> Matching:
    """Matching sets of every seeker, written into ``directory`` (see the module docstring for the method).

    Origins are independent, so they are processed by a few threads (numpy's
    sorts and the compiled kernels release the GIL) and written in OD order:
    the files do not depend on the number of threads.  ``estimate`` is first
    called with the estimated number of pairs (:meth:`_Builder.sample_pairs`)
    and the bytes a pair's local class number takes.
    """
    t0 = time.perf_counter()
    writer = _ListWriter(directory, len(rates), space.class_size)
    origin = rates.origin
    stats = {"stage1_candidates": 0, "stage1_kept": 0, "group_queries": 0}
    try:
        builder = _Builder(space, rates, dist, params, config) if len(origin) else None
        if estimate is not None:
            estimate(builder.sample_pairs() if builder is not None else 0, writer.localizer.dtype.itemsize)
        if builder is not None:
            bounds = np.flatnonzero(np.diff(origin)) + 1
            starts = np.concatenate([[0], bounds]).astype(np.int64)
            ends = np.concatenate([bounds, [len(origin)]]).astype(np.int64)
            tasks = [(int(origin[w0]), int(w0), int(w1)) for w0, w1 in zip(starts, ends, strict=True)]
            bar = tqdm(
                total=len(origin), desc="prediction structure", unit="OD", file=sys.stderr, leave=False, disable=None
            )  # off when stderr is not a terminal
            with bar, ThreadPoolExecutor(max(1, get_num_threads())) as pool:
                for (_, w0, w1), lists in zip(tasks, _in_order(pool, builder.origin_lists, tasks), strict=True):
                    writer.append(w0, lists.lens, lists.classes)
                    for key, value in lists.stats.items():
                        stats[key] += value
                    bar.update(w1 - w0)
        seeker_off, local_dtype = writer.finish()
    finally:
        writer.close()
    stats["state_pairs"] = writer.localizer.state_pairs  # Σ_s |T_s|, for reports
    geometry = ListGeometry.of(space, rates, params, config, lambda: dist)
    matching = Matching.open(directory, seeker_off, stats, local_dtype, geometry)
    matching.stats["build_s"] = time.perf_counter() - t0
    return matching


def _in_order(pool: ThreadPoolExecutor, fn, tasks, ahead: int = 4):
    """``fn(*task)`` for each task, computed by ``pool`` at most ``ahead`` tasks in advance, yielded in order."""
    pending: deque = deque()
    for task in tasks:
        pending.append(pool.submit(fn, *task))
        if len(pending) > ahead:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


@dataclass(frozen=True, eq=False)
class _OriginLists:
    """The sorted lists of the seekers of one origin: pairs per seeker and their global classes."""

    lens: np.ndarray
    classes: np.ndarray
    stats: dict


class _ListWriter:
    """Appends the per-seeker lists, in OD order, through a :class:`~.blocks.Localizer` to ``local.bin``
    and ``blocks.npz``."""

    def __init__(self, directory: Path, n_od: int, class_size: np.ndarray) -> None:
        self.n_od = n_od
        self.directory = directory
        self.file = open(directory / "local.bin", "w+b")  # noqa: SIM115 (closed by close())
        self.localizer = Localizer(len(class_size), self.file, class_size=class_size)
        self.next = 0  # next seeker expected
        self.lens: list[np.ndarray] = []

    def append(self, w0: int, lens: np.ndarray, classes: np.ndarray | None = None) -> None:
        """Seekers ``w0 .. w0+len(lens)-1`` with ``lens`` pairs each and their pairs' global classes."""
        assert w0 == self.next, "seekers must be written in OD order"
        lens = np.asarray(lens, dtype=np.int64)
        self.lens.append(lens)
        self.next = w0 + len(lens)
        self.localizer.append(lens, np.zeros(0, dtype=np.int32) if classes is None else classes)

    def finish(self) -> tuple[np.ndarray, str]:
        """The seekers' offsets (int64, W+1) and the dtype of the local numbers, once every seeker is
        written (the rest get empty lists)."""
        if self.next < self.n_od:
            self.append(self.next, np.zeros(self.n_od - self.next, dtype=np.int64))
        self.localizer.finish().save(self.directory)
        self.close()
        seeker_off = offsets_from_counts(np.concatenate(self.lens) if self.lens else np.zeros(0, dtype=np.int64))
        return seeker_off, self.localizer.dtype.str

    def close(self) -> None:
        self.file.close()


class _Builder:
    """Per-origin construction of the sorted matching lists."""

    def __init__(
        self, space: StateSpace, rates: OdRates, dist: np.ndarray, params: Params, config: PredictConfig
    ) -> None:
        self.space, self.config = space, config
        self.dist = dist
        # l(h, o) by destination: rows of the transpose are what the column reads of ``dist`` would be,
        # contiguous (one copy of the matrix, 122 MB for Haikou, instead of strided gathers per origin).
        self.dist_to = np.ascontiguousarray(dist.T)
        self.r_lim = params.max_pickup_m + TOLERANCE_M
        self.d_lim = params.max_detour_m + TOLERANCE_M
        self.dest = rates.destination.astype(np.int64)
        self.origin = rates.origin
        self.solo = space.solo_m
        if np.any(np.diff(space.class_head) < 0):
            raise ValueError("taker classes must be numbered by head node")
        self.head_off = offsets_from_counts(np.bincount(space.class_head, minlength=dist.shape[0]))

    def sample_pairs(self, samples: int = SIZE_SAMPLES) -> int:
        """The number of pairs of all seekers, estimated from the lists of ``samples`` seekers spread evenly
        over the OD order (all of them when there are fewer)."""
        n_od = len(self.dest)
        seekers = np.unique(np.linspace(0, n_od - 1, min(samples, n_od)).astype(np.int64))
        origin = self.origin
        found = sum(int(self.origin_lists(int(origin[w]), int(w), int(w) + 1).lens.sum()) for w in seekers)
        return round(found * n_od / len(seekers))

    # ------------------------------------------------------------------ stage 1
    def origin_lists(self, o: int, w0: int, w1: int) -> _OriginLists:
        """Sorted lists of the seekers ``w0..w1-1`` (all with origin ``o``); safe to call from threads."""
        sp, cfg = self.space, self.config
        to_o = self.dist_to[o]  # l(h, o) for every node h
        near = np.flatnonzero(to_o <= self.r_lim)  # within R̄ of the seekers
        cand = expand_ranges(self.head_off[near], self.head_off[near + 1])  # sorted by class index
        stats = {"stage1_candidates": len(cand), "stage1_kept": 0, "group_queries": 0}
        row_o = self.dist[o]
        p = to_o[sp.class_head[cand]]
        pk = sp.class_pre_m[cand] + p
        rest = sp.class_rest_m[cand]
        d_a = sp.class_dest[cand]
        a = p - rest
        keep = (pk <= self.r_lim) & (a + row_o[d_a] <= self.d_lim)  # pick-up; FOFO detour of A
        if not cfg.keep_nonpositive:
            keep &= a < 0  # E <= l(h,d_A) - p
        kept = np.flatnonzero(keep)  # one pass over the mask serves the five gathers
        if not len(kept):
            return _OriginLists(np.zeros(w1 - w0, dtype=np.int64), np.zeros(0, dtype=np.int32), stats)
        g = _Group(cand[kept], a[kept], pk[kept], rest[kept], d_a[kept], row_o)
        stats["stage1_kept"] = g.n
        pieces = self._pieces(g, w0, w1)
        stats["group_queries"] = pieces.searches
        lens, classes = self._emit(g, w0, w1, pieces)
        return _OriginLists(lens, classes, stats)

    # ------------------------------------------------------------------ stage 2
    def _pieces(self, g: _Group, w0: int, w1: int) -> _Pieces:
        """Runs of feasible classes per (seeker, d_A group, service order), grouped by seeker (compiled:
        :func:`.kernels.feasible_runs`)."""
        m, n_u = w1 - w0, len(g.dest)
        d_b = self.dest[w0:w1]
        # The seekers' rows of l(d_B, .) and l(., d_B), copied once: contiguous reads, where gathers from
        # the whole 122 MB matrices would miss the cache on nearly every cell.
        from_b, to_b = self.dist.take(d_b, axis=0), self.dist_to.take(d_b, axis=0)
        capacity = m * n_u + 64  # about a third of the (seeker, group) cells hold a run here
        while True:
            out = _Pieces.empty(capacity)
            k, searches = kernels.feasible_runs(
                from_b,
                to_b,
                self.solo[w0:w1],
                g.dest,
                g.d_oa,
                g.a,
                g.start,
                g.size,
                self.d_lim,
                self.config.keep_nonpositive,
                self.config.order_rule == "min_feasible",
                out.row,
                out.start,
                out.n,
                out.g,
                out.shared,
                out.det,
            )
            if k >= 0:
                return out.head(k, searches)
            capacity = 2 * m * n_u  # at most two runs (FOLO, FOFO) per cell

    def _emit(self, g: _Group, w0: int, w1: int, pc: _Pieces) -> tuple[np.ndarray, np.ndarray]:
        """Pairs per seeker and their sorted classes: pieces expanded, prioritised and sorted a batch at a time."""
        m = w1 - w0
        per_row = np.bincount(pc.row, weights=pc.n, minlength=m).astype(np.int64)
        cum = np.cumsum(per_row)
        n = int(cum[-1]) if m else 0
        classes = np.empty(n, dtype=np.int32)
        r0 = 0
        while r0 < m:
            base = cum[r0 - 1] if r0 else 0
            r1 = int(np.searchsorted(cum, base + SORT_ENTRIES, side="right"))
            r1 = min(m, max(r1, r0 + 1), r0 + g.rows_per_sort)
            i0, i1 = (int(i) for i in np.searchsorted(pc.row, [r0, r1]))
            total = int(cum[r1 - 1] - base)
            if total:
                self._sorted_entries(g, pc, i0, i1, r0, w0, classes[base : base + total])
            r0 = r1
        return per_row, classes

    def _sorted_entries(self, g: _Group, pc: _Pieces, i0: int, i1: int, r0: int, w0: int, out: np.ndarray) -> None:
        """Pieces ``i0..i1-1`` (seeker rows from ``r0``) expanded, sorted, and their classes written into ``out``.

        The sort key (row | descending priority | tie rank) is unique and names
        its entry: the tie rank names the class survivor, and a survivor lies in
        one piece of its row.  So the keys themselves are sorted (a SIMD sort,
        several times faster than an argsort) and their tie ranks give the classes.
        """
        rows, start, n = pc.row[i0:i1] - r0, pc.start[i0:i1], pc.n[i0:i1]
        keys = np.empty(int(n.sum()), dtype=np.uint64)
        packable = 64 - Q_BITS - g.tie_bits >= max(1, int(rows.max()).bit_length())
        piece = col = None
        if self.config.priority == "net_saving":  # E - pk = g - a - pk, computed in the kernel
            packable = packable and kernels.net_saving_keys(
                rows, start, n, pc.g[i0:i1], g.kappa, g.tie_rank, g.tie_bits, Q_BITS, GRID, _Q_LIMIT, keys
            )
            prio = None
        else:
            piece, col = np.repeat(np.arange(i0, i1), n), expand_ranges(start, start + n)
            prio = _priority(
                self.config.priority,
                pc.g[piece] - g.a[col],
                g.pk[col],
                pc.shared[piece],
                pc.det[piece],
                g.rest[col],
                self.solo[w0 + pc.row[piece]],
            )
            packable = packable and _pack_keys(rows, n, prio, g.tie_rank[col], g.tie_bits, keys)
        if packable:
            keys.sort()
            keys &= np.uint64((1 << g.tie_bits) - 1)  # the tie ranks
            np.take(g.cls_by_rank, keys.view(np.int64), out=out)
            return
        # Huge distances (beyond 2^18 m) or huge groups: the same order through a slower lexsort.
        if piece is None or col is None:
            piece, col = np.repeat(np.arange(i0, i1), n), expand_ranges(start, start + n)
        if prio is None:
            prio = pc.g[piece] + g.kappa[col]
        perm = np.lexsort((g.tie_rank[col], np.floor(np.multiply(prio, -GRID)), np.repeat(rows, n)))
        np.take(g.cls, col[perm], out=out)


@dataclass(frozen=True, eq=False)
class _Pieces:
    """Runs ``[start, start + n)`` of survivors, one per (seeker row, group, service order), sorted by row."""

    row: np.ndarray  # seeker row of each run
    start: np.ndarray  # first survivor of the run
    n: np.ndarray  # run length
    g: np.ndarray  # E + a on the run (float64)
    shared: np.ndarray  # shared distance on the run (float32)
    det: np.ndarray  # seeker detour on the run (float32)
    searches: int = 0  # binary searches the runs took

    @classmethod
    def empty(cls, capacity: int) -> _Pieces:
        return cls(
            row=np.empty(capacity, dtype=np.int64),
            start=np.empty(capacity, dtype=np.int64),
            n=np.empty(capacity, dtype=np.int64),
            g=np.empty(capacity),
            shared=np.empty(capacity, dtype=np.float32),
            det=np.empty(capacity, dtype=np.float32),
        )

    def head(self, k: int, searches: int) -> _Pieces:
        """The first ``k`` runs (copies: the rest of the buffers is freed)."""
        return _Pieces(
            row=self.row[:k].copy(),
            start=self.start[:k].copy(),
            n=self.n[:k].copy(),
            g=self.g[:k].copy(),
            shared=self.shared[:k].copy(),
            det=self.det[:k].copy(),
            searches=searches,
        )


class _Group:
    """Stage-1 survivors of one origin, sorted by (d_A, a): each destination group's ``a`` ascend, so
    :func:`.kernels.feasible_runs` counts a group's feasible classes exactly by binary search."""

    def __init__(self, cls, a, pk, rest, dest, row_o):
        n = len(a)
        # (d_A, a) order: a quicksort on a, then a stable radix pass on the destination.  (The quicksort's
        # order among equal a is part of the stored lists' order: keep this exact sequence of sorts.)
        by_a = np.argsort(a)
        dkey = dest[by_a]
        order = by_a[np.argsort(dkey.astype(np.uint16) if dkey.max() < 65536 else dkey, kind="stable")]
        self.n = n
        self.cls = cls[order].astype(np.int32)
        self.a, self.pk, self.rest = a[order], pk[order], rest[order]
        dest = dest[order]
        self.kappa = -self.a - self.pk  # E - pk = g + kappa
        new = np.ones(n, dtype=bool)
        new[1:] = dest[1:] != dest[:-1]
        self.start = np.flatnonzero(new).astype(np.int64)
        self.size = np.diff(np.append(self.start, n))
        self.dest = dest[self.start].astype(np.int64)
        self.d_oa = row_o[self.dest]  # l(o, d_A) per group
        # Tie ranks: ascending pk on the priority grid, then class index (the survivors arrive in class
        # order, so the pre-sort position breaks ties).
        pk_q = np.floor(pk * GRID).astype(np.int64)
        if n < (1 << 25) and pk_q.max() < (1 << 38):
            tie = np.argsort((pk_q[order] << 25) | order)
        else:
            tie = np.lexsort((order, pk_q[order]))
        self.tie_rank = np.empty(n, dtype=np.int64)
        self.tie_rank[tie] = np.arange(n)
        self.cls_by_rank = self.cls[tie]  # decodes the sorted keys
        self.tie_bits = max(1, int(n).bit_length())
        row_bits = 64 - Q_BITS - self.tie_bits
        self.rows_per_sort = 1 << row_bits if row_bits >= 1 else 1  # 1: _sorted_entries falls back to lexsort


def _priority(kind: str, e, pk, shared, seeker_detour, rest, l_b) -> np.ndarray:
    """Priority value of each entry, larger = served first (§2.4)."""
    if kind == "net_saving":
        return e - pk
    if kind == "fl_utility":  # e²/(e+pk), the FL V1 utility (Eq. 13) without α^k;
        with np.errstate(divide="ignore", invalid="ignore"):  # e <= 0 (kept on request): e, continuous at 0
            return np.where(e > 0, e * e / (e + pk), e)
    if kind == "pickup":  # nearest first (the TR-B simulators)
        return -pk
    if kind == "vehicle_distance":  # ascending distance the vehicle drives from h
        return -(rest + l_b - e)
    # authors_feng_grid: -0.5 detour - 0.3 pickup + 0.2 shared (detour = both passengers')
    taker_detour = shared - e - seeker_detour
    return -0.5 * (seeker_detour + taker_detour) - 0.3 * pk + 0.2 * shared


def _pack_keys(piece_row, piece_len, prio, tie_rank, tie_bits: int, keys: np.ndarray) -> bool:
    """Fill ``keys`` with (row | quantised descending priority | tie rank); False when they do not fit 64 bits."""
    if len(prio) and not np.abs(prio).max() < _Q_LIMIT:
        return False
    desc = np.multiply(prio, -GRID)
    desc += float(1 << (Q_BITS - 1))  # in (0, 2^Q_BITS): larger priority, smaller key
    keys[:] = desc.astype(np.uint64)  # positive: truncation is the floor
    keys <<= np.uint64(tie_bits)
    keys |= tie_rank.astype(np.uint64)
    keys |= np.repeat(piece_row.astype(np.uint64) << np.uint64(Q_BITS + tie_bits), piece_len)
    return True
