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

**Storage.**  Per pair: the class, as a block-local number (uint16, see
:mod:`.blocks`), the saving ``E`` (float32: sub-millimetre rounding at urban
distances; the fixed point only uses the order of the classes) and the
pair's *piece* within its seeker (uint16), 8 bytes a pair, appended origin
by origin to one raw file per column (see :mod:`.list_cache`, which keeps them
in the cache) and read back as read-only memory maps.  The shared distance
and the seeker's detour are the same along a piece (one seeker, one
destination group, one service order: about 25 pairs on the month table), so
they are stored once per piece, in float32, in per-piece columns.  The taker's detour is
``shared - E - detour_seeker`` and its ride from ``h`` is
``l(h,d_A) - E - detour_seeker + shared``.

**Speed.**  Origins are independent and run in a few threads.  Sorting
(step 3) sorts the packed keys themselves, not an index: a key is unique and
names its entry (the tie rank names the class survivor, which lies in one
piece of its seeker's row), so a compiled pass (:mod:`.kernels`) decodes the
sorted keys into the columns.
"""

from __future__ import annotations

import mmap
import sys
import time
from collections import deque
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
CHUNK_PAIRS = 1 << 24  # pairs per chunk when the sweeps stream the columns

#: The per-pair distance columns (name, dtype), each stored as one raw little-endian file ``<name>.bin``;
#: the classes are stored as ``local.bin`` (block-local numbers, uint16 or int32) and ``blocks.npz``, the
#: pairs' pieces as ``piece.bin``, and the per-piece columns as ``piece_<name>.bin`` with ``piece_off.npy``.
COLUMNS = (("saving_m", "<f4"),)
PIECE_COLUMNS = (("shared_m", "<f4"), ("detour_m", "<f4"))  # the seeker's detour


def piece_dtype(n_nodes: int) -> np.dtype:
    """Piece numbers within a seeker: at most two pieces (FOFO, FOLO) per destination node."""
    return np.dtype("<u2") if 2 * n_nodes <= (1 << 16) else np.dtype("<u4")


@dataclass(frozen=True, eq=False)
class Matching:
    """Each seeker's taker classes in priority order, as flat CSR columns (usually memory maps).

    The pairs of seeker ``s(w)`` are ``[seeker_off[w], seeker_off[w+1])`` of
    every column.  The columns are read-only maps of the files in
    :attr:`directory` (see :mod:`.list_cache`): several processes share one
    copy in the page cache, and a sweep only brings in what it touches.
    """

    seeker_off: np.ndarray  # int64 (W+1)
    local: np.ndarray  # uint16 (or int32) taker class per pair, numbered within its block
    saving_m: np.ndarray  # float32 E(s, t)
    piece: np.ndarray  # uint16 (or uint32) the pair's piece, numbered within its seeker
    piece_off: np.ndarray  # int64 (W+1): seeker s's pieces are piece_off[s] .. piece_off[s+1]-1
    piece_shared_m: np.ndarray  # float32 shared distance, per piece
    piece_detour_m: np.ndarray  # float32 detour of the seeker, per piece
    blocks: ClassBlocks  # the seekers' blocks and the global class of each local number
    stats: dict = field(default_factory=dict)

    @classmethod
    def from_lists(
        cls,
        seeker_off,
        classes,
        saving_m,
        shared_m,
        seeker_detour_m,
        *,
        n_classes: int | None = None,
        limit: int = BLOCK_CLASSES,
    ) -> Matching:
        """A matching held in memory, from global class lists and per-pair distances, one piece per pair
        (tests and small models)."""
        seeker_off = np.asarray(seeker_off, dtype=np.int64)
        classes = np.asarray(classes, dtype=np.int32)
        if n_classes is None:
            n_classes = int(classes.max()) + 1 if len(classes) else 0
        local, blocks = localize_lists(seeker_off, classes, n_classes, limit)
        lens = np.diff(seeker_off)
        wide = len(lens) and int(lens.max()) > (1 << 16)
        piece = (np.arange(len(classes)) - np.repeat(seeker_off[:-1], lens)).astype("<u4" if wide else "<u2")
        return cls(
            seeker_off=seeker_off,
            local=local,
            saving_m=np.asarray(saving_m, dtype=np.float32),
            piece=piece,
            piece_off=seeker_off.copy(),
            piece_shared_m=np.asarray(shared_m, dtype=np.float32),
            piece_detour_m=np.asarray(seeker_detour_m, dtype=np.float32),
            blocks=blocks,
        )

    @property
    def cls(self) -> np.ndarray:
        """The taker class of every pair (int32, computed in memory: for tests and small models)."""
        return self.blocks.classes(self.local, self.seeker_off, 0, len(self.seeker_off) - 1)

    @property
    def shared_m(self) -> np.ndarray:
        """The shared distance of every pair (float32, expanded in memory: tests and small models)."""
        return self.piece_shared_m[self._global_piece(0, len(self.seeker_off) - 1)]

    @property
    def seeker_detour_m(self) -> np.ndarray:
        """The seeker's detour of every pair (float32, expanded in memory: tests and small models)."""
        return self.piece_detour_m[self._global_piece(0, len(self.seeker_off) - 1)]

    def _global_piece(self, s0: int, s1: int) -> np.ndarray:
        """Index into the piece table of every pair of seekers ``s0..s1-1``."""
        off = self.seeker_off
        i0, i1 = int(off[s0]), int(off[s1])
        return np.repeat(self.piece_off[s0:s1], np.diff(off[s0 : s1 + 1])) + self.piece[i0:i1]

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
        return int(
            self.seeker_off.nbytes
            + self.local.nbytes
            + self.piece.nbytes
            + self.piece_off.nbytes
            + self.piece_shared_m.nbytes
            + self.piece_detour_m.nbytes
            + sum(getattr(self, name).nbytes for name, _ in COLUMNS)
        )

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
        """Give back this process's pages of the pairs and pieces of seekers ``s0..s1-1`` (every column)."""
        self.release(int(self.seeker_off[s0]), int(self.seeker_off[s1]), ("local", "saving_m", "piece"))
        self.release(int(self.piece_off[s0]), int(self.piece_off[s1]), ("piece_shared_m", "piece_detour_m"))

    def release(self, i0: int, i1: int, names: tuple[str, ...]) -> None:
        """Give back this process's pages of entries ``[i0, i1)`` of the named memory-mapped columns.

        The data stays in the page cache (a later read maps it again), but a
        pass over 2.3 GB of columns no longer leaves them all resident.
        Columns that are not memory maps are left alone.
        """
        for name in names:
            col = getattr(self, name)
            mapped = getattr(col, "_mmap", None)  # numpy keeps the mmap object of a np.memmap here
            if mapped is None or not hasattr(mapped, "madvise"):
                continue
            start = i0 * col.itemsize // mmap.PAGESIZE * mmap.PAGESIZE  # the columns are mapped from byte 0
            end = min(i1 * col.itemsize, len(mapped))
            if end > start:
                mapped.madvise(mmap.MADV_DONTNEED, start, end - start)

    def seeker(self, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(classes, E, shared, seeker detour) of seeker ``s(w)``, in priority order."""
        i0, i1 = self.seeker_off[w], self.seeker_off[w + 1]
        classes = self.blocks.classes(self.local, self.seeker_off, w, w + 1)
        pieces = self._global_piece(w, w + 1)
        return classes, self.saving_m[i0:i1], self.piece_shared_m[pieces], self.piece_detour_m[pieces]

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All pairs in OD order as in-memory arrays: classes, E, shared, seeker detour (tests, small models)."""
        pieces = self._global_piece(0, len(self.seeker_off) - 1)
        return self.cls, np.array(self.saving_m), self.piece_shared_m[pieces], self.piece_detour_m[pieces]

    @classmethod
    def open(cls, directory: Path, seeker_off: np.ndarray, stats: dict, dtypes: dict) -> Matching:
        """The matching whose columns lie in ``directory`` (read-only memory maps); ``dtypes`` names the
        dtypes of the ``local`` and ``piece`` numbers."""
        n, n_od = int(seeker_off[-1]), len(seeker_off) - 1
        if np.dtype(dtypes["local"]) not in (np.dtype("<u2"), np.dtype("<i4")):
            raise ValueError(f"local class numbers of type {dtypes['local']!r} are not supported")
        if np.dtype(dtypes["piece"]) not in (np.dtype("<u2"), np.dtype("<u4")):
            raise ValueError(f"piece numbers of type {dtypes['piece']!r} are not supported")
        columns = {name: _open_column(directory / f"{name}.bin", dtype, n) for name, dtype in COLUMNS}
        local = _open_column(directory / "local.bin", dtypes["local"], n)
        piece = _open_column(directory / "piece.bin", dtypes["piece"], n)
        piece_off = np.load(directory / "piece_off.npy", allow_pickle=False)
        if len(piece_off) != n_od + 1 or piece_off[0] != 0 or np.any(np.diff(piece_off) < 0):
            raise ValueError("its piece offsets are inconsistent")
        table = {
            f"piece_{name}": _open_column(directory / f"piece_{name}.bin", dtype, int(piece_off[-1]))
            for name, dtype in PIECE_COLUMNS
        }
        blocks = ClassBlocks.load(directory, n_od)
        return cls(
            seeker_off=seeker_off,
            stats=stats,
            local=local,
            piece=piece,
            piece_off=piece_off,
            blocks=blocks,
            **columns,
            **table,
        )


def _open_column(path: Path, dtype: str, n: int) -> np.ndarray:
    if path.stat().st_size != n * np.dtype(dtype).itemsize:
        raise ValueError(f"{path.name} holds {path.stat().st_size} bytes, expected {n} {dtype} values")
    if n == 0:  # an empty file cannot be mapped
        return np.zeros(0, dtype=dtype)
    return np.memmap(path, dtype=dtype, mode="r", shape=(n,))


def build_matching(
    space: StateSpace, rates: OdRates, dist: np.ndarray, params: Params, config: PredictConfig, directory: Path
) -> Matching:
    """Matching sets of every seeker, written into ``directory`` (see the module docstring for the method).

    Origins are independent, so they are processed by a few threads (numpy's
    sorts and the compiled kernels release the GIL) and written in OD order:
    the files do not depend on the number of threads.
    """
    t0 = time.perf_counter()
    writer = _ColumnWriter(directory, len(rates), space.class_size, piece_dtype(dist.shape[0]))
    origin = rates.origin
    stats = {"stage1_candidates": 0, "stage1_kept": 0, "group_queries": 0}
    try:
        if len(origin):
            builder = _Builder(space, rates, dist, params, config)
            bounds = np.flatnonzero(np.diff(origin)) + 1
            starts = np.concatenate([[0], bounds]).astype(np.int64)
            ends = np.concatenate([bounds, [len(origin)]]).astype(np.int64)
            tasks = [(int(origin[w0]), int(w0), int(w1)) for w0, w1 in zip(starts, ends, strict=True)]
            bar = tqdm(
                total=len(origin), desc="prediction structure", unit="OD", file=sys.stderr, leave=False, disable=None
            )  # off when stderr is not a terminal
            with bar, ThreadPoolExecutor(max(1, get_num_threads())) as pool:
                for (_, w0, w1), lists in zip(tasks, _in_order(pool, builder.origin_lists, tasks), strict=True):
                    writer.append(w0, lists.lens, lists.columns, lists.pieces)
                    for key, value in lists.stats.items():
                        stats[key] += value
                    bar.update(w1 - w0)
        seeker_off, dtypes = writer.finish()
    finally:
        writer.close()
    stats["state_pairs"] = writer.localizer.state_pairs  # Σ_s |T_s|, for reports
    matching = Matching.open(directory, seeker_off, stats, dtypes)
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
    """The sorted lists of the seekers of one origin: pairs per seeker, the pair columns (class, E, piece)
    and the piece table (pieces per seeker, shared distance, seeker detour)."""

    lens: np.ndarray
    columns: tuple[np.ndarray, ...]
    pieces: tuple[np.ndarray, ...]
    stats: dict


class _ColumnWriter:
    """Appends the per-seeker lists, in OD order, to one raw file per column; the classes go through
    a :class:`~.blocks.Localizer` into ``local.bin`` and ``blocks.npz``, the pieces' distances into
    ``piece_<name>.bin`` and their counts into ``piece_off.npy``."""

    def __init__(self, directory: Path, n_od: int, class_size: np.ndarray, piece_dtype: np.dtype) -> None:
        self.n_od = n_od
        self.directory = directory
        self.piece_dtype = np.dtype(piece_dtype)
        self.files = {name: open(directory / f"{name}.bin", "wb") for name, _ in COLUMNS}  # noqa: SIM115 (closed by close())
        self.files["piece"] = open(directory / "piece.bin", "wb")  # noqa: SIM115 (closed by close())
        self.files.update({f"piece_{name}": open(directory / f"piece_{name}.bin", "wb") for name, _ in PIECE_COLUMNS})  # noqa: SIM115 (closed by close())
        self.files["local"] = open(directory / "local.bin", "w+b")  # noqa: SIM115 (closed by close())
        self.localizer = Localizer(len(class_size), self.files["local"], class_size=class_size)
        self.next = 0  # next seeker expected
        self.lens: list[np.ndarray] = []
        self.piece_counts: list[np.ndarray] = []

    def append(
        self, w0: int, lens: np.ndarray, columns: tuple[np.ndarray, ...] = (), pieces: tuple[np.ndarray, ...] = ()
    ) -> None:
        """Seekers ``w0 .. w0+len(lens)-1`` with ``lens`` pairs each, their pairs' columns (global
        classes, E, piece) and their piece table (pieces per seeker, shared distance, seeker detour)."""
        assert w0 == self.next, "seekers must be written in OD order"
        lens = np.asarray(lens, dtype=np.int64)
        self.lens.append(lens)
        self.next = w0 + len(lens)
        classes, saving, piece = columns or (np.zeros(0, dtype=np.int32), np.zeros(0), np.zeros(0))
        self.localizer.append(lens, classes)
        self.files["saving_m"].write(memoryview(np.ascontiguousarray(saving, dtype=COLUMNS[0][1])))
        self.files["piece"].write(memoryview(np.ascontiguousarray(piece, dtype=self.piece_dtype)))
        counts, *table = pieces or (np.zeros(len(lens), dtype=np.int64), np.zeros(0), np.zeros(0))
        self.piece_counts.append(np.asarray(counts, dtype=np.int64))
        for (name, dtype), values in zip(PIECE_COLUMNS, table, strict=True):
            self.files[f"piece_{name}"].write(memoryview(np.ascontiguousarray(values, dtype=dtype)))

    def finish(self) -> tuple[np.ndarray, dict]:
        """The seekers' offsets (int64, W+1) and the dtypes of the local and piece numbers, once every
        seeker is written (the rest get empty lists)."""
        if self.next < self.n_od:
            self.append(self.next, np.zeros(self.n_od - self.next, dtype=np.int64))
        self.localizer.finish().save(self.directory)
        counts = np.concatenate(self.piece_counts) if self.piece_counts else np.zeros(0, dtype=np.int64)
        np.save(self.directory / "piece_off.npy", offsets_from_counts(counts))
        self.close()
        seeker_off = offsets_from_counts(np.concatenate(self.lens) if self.lens else np.zeros(0, dtype=np.int64))
        return seeker_off, {"local": self.localizer.dtype.str, "piece": self.piece_dtype.str}

    def close(self) -> None:
        for fh in self.files.values():
            fh.close()


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
        self.piece_dtype = piece_dtype(dist.shape[0])
        self.solo = space.solo_m
        if np.any(np.diff(space.class_head) < 0):
            raise ValueError("taker classes must be numbered by head node")
        self.head_off = offsets_from_counts(np.bincount(space.class_head, minlength=dist.shape[0]))

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
            return _OriginLists(np.zeros(w1 - w0, dtype=np.int64), (), (), stats)
        g = _Group(cand[kept], a[kept], pk[kept], rest[kept], d_a[kept], row_o)
        stats["stage1_kept"] = g.n
        pieces = self._pieces(g, w0, w1)
        stats["group_queries"] = pieces.searches
        lens, columns = self._emit(g, w0, w1, pieces)
        table = (np.bincount(pieces.row, minlength=w1 - w0), pieces.shared, pieces.det)  # pieces are by row
        return _OriginLists(lens, columns, table, stats)

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

    def _emit(self, g: _Group, w0: int, w1: int, pc: _Pieces) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """Pairs per seeker and the sorted columns: pieces expanded, prioritised and sorted a batch at a time."""
        m = w1 - w0
        per_row = np.bincount(pc.row, weights=pc.n, minlength=m).astype(np.int64)
        cum = np.cumsum(per_row)
        n = int(cum[-1]) if m else 0
        columns = (np.empty(n, dtype=np.int32), np.empty(n, dtype=COLUMNS[0][1]), np.empty(n, dtype=self.piece_dtype))
        r0 = 0
        while r0 < m:
            base = cum[r0 - 1] if r0 else 0
            r1 = int(np.searchsorted(cum, base + SORT_ENTRIES, side="right"))
            r1 = min(m, max(r1, r0 + 1), r0 + g.rows_per_sort)
            i0, i1 = (int(i) for i in np.searchsorted(pc.row, [r0, r1]))
            total = int(cum[r1 - 1] - base)
            if total:
                self._sorted_entries(g, pc, i0, i1, r0, w0, tuple(c[base : base + total] for c in columns))
            r0 = r1
        return per_row, columns

    def _sorted_entries(self, g: _Group, pc: _Pieces, i0: int, i1: int, r0: int, w0: int, out) -> None:
        """Pieces ``i0..i1-1`` (seeker rows from ``r0``) expanded, sorted and written into ``out``.

        The sort key (row | descending priority | tie rank) is unique and names
        its entry: the tie rank names the class survivor, and a survivor lies in
        one piece of its row.  So the keys themselves are sorted (a SIMD sort,
        several times faster than an argsort) and decoded by a compiled pass.
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
        cls, saving, piece_out = out
        if packable:
            keys.sort()
            kernels.decode_entries(
                keys, g.tie_bits, rows, start, n, pc.g[i0:i1], g.tie_rank, g.by_rank, cls, saving, piece_out
            )
            return
        # Huge distances (beyond 2^18 m) or huge groups: the same order through a slower lexsort.
        if piece is None:
            piece, col = np.repeat(np.arange(i0, i1), n), expand_ranges(start, start + n)
        if prio is None:
            prio = pc.g[piece] + g.kappa[col]
        perm = np.lexsort((g.tie_rank[col], np.floor(np.multiply(prio, -GRID)), np.repeat(rows, n)))
        col, piece = col[perm], piece[perm]
        np.take(g.cls, col, out=cls)
        np.subtract(pc.g[piece], g.a[col], out=saving, casting="same_kind")
        first_of_row = np.searchsorted(pc.row, pc.row[piece], side="left")  # pieces are sorted by row
        piece_out[:] = piece - first_of_row


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
        # Per tie rank: the survivor's (a, class, piece scratch) in one row, for decoding sorted keys
        # (classes < 2^31 and pieces are exact in float64).
        self.by_rank = np.empty((n, int(kernels.RANK_ROW)))
        self.by_rank[:, 0] = self.a[tie]
        self.by_rank[:, 1] = self.cls[tie]
        self.tie_bits = max(1, int(n).bit_length())
        row_bits = 64 - Q_BITS - self.tie_bits
        self.rows_per_sort = 1 << row_bits if row_bits >= 1 else 1  # 1: _sorted_entries falls back to lexsort


def _priority(kind: str, e, pk, shared, seeker_detour, rest, l_b) -> np.ndarray:
    """Priority value of each entry, larger = served first (§2.4)."""
    if kind == "net_saving":
        return e - pk
    if kind == "fl_utility":  # e²/(e+pk), the FL V1 utility (Eq. 15) without α^k;
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
