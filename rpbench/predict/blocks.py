"""Class blocks: the seekers cut into runs whose lists name few enough classes to stay in cache.

A sweep (:mod:`.kernels`) looks up ``Q_c`` and adds to ``H_c`` for every
stored (seeker, class) pair, in list order: random accesses into per-class
arrays of 345 k entries (several megabytes each) on the month table.  The
seekers are therefore cut, in OD order, into *blocks* whose lists together
name at most :data:`BLOCK_CLASSES` classes (seekers of one origin share most
of their takers, so a block spans tens of ODs).  Within a block the classes
are numbered 0, 1, ... in order of first use; a pair stores that *local*
number (uint16), and the block keeps the global class of each local number.
A sweep gathers a block's class values into a small array, walks the block's
pairs against it, and scatters the sums back.

The cut depends only on the lists, never on the machine or the thread
count, so the sums are added in a fixed order.  A seeker whose own list
names more than :data:`BLOCK_CLASSES` classes gets a block of its own and
the local numbers widen to int32 (:class:`Localizer` rewrites what it
already wrote).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import BinaryIO

import numpy as np
from numba import get_num_threads

from rpbench.predict import kernels

#: Classes a block may name: local numbers fit 16 bits, and a block's gathered values
#: (8 bytes each, three arrays in a sweep) stay within a core's 2-4 MB cache.
BLOCK_CLASSES = 1 << 16
#: Local numbers stay 16-bit while no block names more classes than this.
NARROW_LIMIT = 1 << 16


@dataclass(frozen=True, eq=False)
class ClassBlocks:
    """Block b: seekers ``seeker_off[b]..seeker_off[b+1]-1``, classes ``cls[cls_off[b]:cls_off[b+1]]``."""

    seeker_off: np.ndarray  # int64 (B+1)
    cls: np.ndarray  # int32: the global class of each (block, local number)
    cls_off: np.ndarray  # int64 (B+1)

    @property
    def n_blocks(self) -> int:
        return len(self.seeker_off) - 1

    @cached_property  # asked for by every sweep
    def width(self) -> int:
        """Classes of the widest block (the gather buffers' length)."""
        return int(np.diff(self.cls_off).max()) if self.n_blocks else 0

    def chunks(self, pair_off: np.ndarray, max_pairs: int) -> np.ndarray:
        """Block boundaries ``[0, b1, b2, ..., B]`` of consecutive runs of about ``max_pairs`` pairs
        (at least one block each): the fixed work units of the parallel sweeps."""
        first_pair = pair_off[self.seeker_off]
        bounds = [0]
        while bounds[-1] < self.n_blocks:
            b0 = bounds[-1]
            b1 = int(np.searchsorted(first_pair, first_pair[b0] + max_pairs, side="right")) - 1
            bounds.append(min(self.n_blocks, max(b1, b0 + 1)))
        return np.asarray(bounds, dtype=np.int64)

    def classes(self, local: np.ndarray, pair_off: np.ndarray, s0: int, s1: int) -> np.ndarray:
        """Global classes of the pairs of seekers ``s0..s1-1`` (int32, in memory)."""
        base = int(pair_off[s0])
        out = np.empty(int(pair_off[s1]) - base, dtype=np.int32)
        b = int(np.searchsorted(self.seeker_off, s0, side="right")) - 1
        while b < self.n_blocks and self.seeker_off[b] < s1:
            lo, hi = max(s0, int(self.seeker_off[b])), min(s1, int(self.seeker_off[b + 1]))
            i0, i1 = int(pair_off[lo]), int(pair_off[hi])
            table = self.cls[self.cls_off[b] : self.cls_off[b + 1]]
            out[i0 - base : i1 - base] = table[np.asarray(local[i0:i1], dtype=np.int64)]
            b += 1
        return out

    def save(self, directory: Path) -> None:
        np.savez(directory / "blocks.npz", seeker_off=self.seeker_off, cls=self.cls, cls_off=self.cls_off)

    @classmethod
    def load(cls, directory: Path, n_od: int, n_classes: int | None = None) -> ClassBlocks:
        with np.load(directory / "blocks.npz", allow_pickle=False) as data:
            blocks = cls(seeker_off=data["seeker_off"], cls=data["cls"], cls_off=data["cls_off"])
        so, co = blocks.seeker_off, blocks.cls_off
        if (
            so.dtype != np.int64
            or co.dtype != np.int64
            or blocks.cls.dtype != np.int32
            or so.ndim != 1
            or len(so) != len(co)
            or len(so) < 1
            or so[0] != 0
            or so[-1] != n_od
            or co[0] != 0
            or co[-1] != len(blocks.cls)
            or np.any(np.diff(so) < 0)
            or np.any(np.diff(co) < 0)
        ):
            raise ValueError("its class blocks are inconsistent")
        if n_classes is not None and len(blocks.cls) and (blocks.cls.min() < 0 or blocks.cls.max() >= n_classes):
            raise ValueError(f"its class blocks name classes outside 0..{n_classes - 1}")
        return blocks

    def local_problem(self, local: np.ndarray, pair_off: np.ndarray) -> str | None:
        """Where ``local`` names a number beyond its block's classes (None: every pair is in range).

        One compiled pass over the lists (:func:`.kernels.first_bad_block`), split between
        threads; ``pair_off`` and the blocks' offsets must be checked first.
        """
        threads = max(1, get_num_threads())
        bounds = self.chunks(pair_off, max(1, int(pair_off[-1]) // threads + 1))
        with ThreadPoolExecutor(threads) as pool:  # the kernel releases the GIL
            found = pool.map(
                lambda b: kernels.first_bad_block(pair_off, local, self.seeker_off, self.cls_off, b[0], b[1]),
                zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True),
            )
            bad = next((int(b) for b in found if b >= 0), -1)
        if bad < 0:
            return None
        width = int(self.cls_off[bad + 1] - self.cls_off[bad])
        return f"a pair of block {bad} names a class beyond the block's {width}"


class Localizer:
    """Cuts the lists into blocks as they are appended, in OD order, and writes the local numbers.

    ``out`` receives the local numbers (uint16, or int32 once a seeker names
    more than :data:`BLOCK_CLASSES` classes: the numbers written so far are
    then rewritten wider, once).  With ``class_size`` (members per class) it
    also counts Σ_s |T_s|, the seeker-taker *state* pairs, in the same pass.
    """

    def __init__(
        self,
        n_classes: int,
        out: BinaryIO | None = None,
        limit: int = BLOCK_CLASSES,
        class_size: np.ndarray | None = None,
    ) -> None:
        self.limit = int(limit)
        self.out = out
        self.dtype = np.dtype("<u2") if self.limit <= NARROW_LIMIT else np.dtype("<i4")
        # Per class, in one row (one cache line per lookup): the block that last named it, its local
        # number there, and its size.
        self.per_class = np.zeros((max(n_classes, 1), 4), dtype=np.int32)
        self.per_class[:, 0] = -1
        self.per_class[:n_classes, 2] = 1 if class_size is None else class_size
        # open block, its classes, seekers, block classes, Σ class_size over the pairs
        self.state = np.zeros(5, dtype=np.int64)
        self.block_seeker: list[np.ndarray] = [np.zeros(1, np.int64)]
        self.block_pos: list[np.ndarray] = [np.zeros(1, np.int64)]
        self.block_cls: list[np.ndarray] = []
        self.parts: list[np.ndarray] = []  # the local numbers, when there is no file

    def append(self, lens: np.ndarray, cls: np.ndarray) -> np.ndarray:
        """The local numbers of seekers with ``lens`` pairs and global classes ``cls`` (written to ``out``)."""
        lens = np.asarray(lens, dtype=np.int64)
        cls = np.asarray(cls)
        if cls.dtype not in (np.int32, np.int64):  # the kernel reads int32 lists as they are
            cls = cls.astype(np.int64)
        # A block names at most max(limit, the longest list) classes; 16 bits hold NARROW_LIMIT.
        if len(lens) and int(lens.max()) > NARROW_LIMIT and self.dtype.itemsize == 2:
            self._widen()
        local = np.empty(len(cls), dtype=self.dtype)  # written in its final type by the kernel
        new_seeker = np.empty(len(lens) + 1, dtype=np.int64)
        new_pos = np.empty(len(lens) + 1, dtype=np.int64)
        block_cls = np.empty(len(cls), dtype=np.int32)
        n_new, n_cls = kernels.localize(
            lens, cls, self.limit, self.per_class, self.state, local, new_seeker, new_pos, block_cls
        )
        self.block_seeker.append(new_seeker[:n_new].copy())
        self.block_pos.append(new_pos[:n_new].copy())
        self.block_cls.append(block_cls[:n_cls].copy())
        if self.out is None:
            self.parts.append(local)
        else:
            self.out.write(local.data)
        return local

    @property
    def state_pairs(self) -> int:
        """Σ ``class_size`` over the pairs appended so far (the pair count without ``class_size``)."""
        return int(self.state[4])

    def finish(self) -> ClassBlocks:
        seekers, written = int(self.state[2]), int(self.state[3])
        return ClassBlocks(
            seeker_off=np.concatenate(self.block_seeker + [np.array([seekers])]).astype(np.int64),
            cls=np.concatenate(self.block_cls or [np.zeros(0, np.int32)]).astype(np.int32),
            cls_off=np.concatenate(self.block_pos + [np.array([written])]).astype(np.int64),
        )

    def local(self) -> np.ndarray:
        """All local numbers appended (in-memory use only)."""
        return np.concatenate([p.astype(self.dtype) for p in self.parts]) if self.parts else np.zeros(0, self.dtype)

    def _widen(self) -> None:
        """Switch to int32 local numbers, converting those already written."""
        self.dtype = np.dtype("<i4")
        if self.out is None:
            return
        self.out.flush()
        path = Path(self.out.name)
        narrow = np.fromfile(path, dtype="<u2")
        self.out.seek(0)
        self.out.truncate()
        self.out.write(narrow.astype("<i4").data)


def localize_lists(
    seeker_off: np.ndarray, cls: np.ndarray, n_classes: int, limit: int = BLOCK_CLASSES
) -> tuple[np.ndarray, ClassBlocks]:
    """Local numbers and blocks of lists held in memory (tests, small models)."""
    localizer = Localizer(n_classes, limit=limit)
    localizer.append(np.diff(seeker_off), cls)
    return localizer.local(), localizer.finish()
