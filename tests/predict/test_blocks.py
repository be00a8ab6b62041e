"""Class blocks: the cut of the seekers, the local numbers, and their widening."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.predict import blocks as blocks_module
from rpbench.predict.blocks import ClassBlocks, Localizer, localize_lists


def random_lists(seed: int, n_od: int = 60, n_classes: int = 50, longest: int = 15):
    rng = np.random.default_rng(seed)
    lens = rng.integers(0, longest + 1, n_od)
    off = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
    cls = np.concatenate([rng.choice(n_classes, k, replace=False) for k in lens]).astype(np.int32)
    return off, cls


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("limit", [1, 6, 20, 1 << 16])
def test_local_numbers_name_the_classes_and_blocks_respect_the_limit(seed, limit):
    off, cls = random_lists(seed)
    local, blocks = localize_lists(off, cls, 50, limit)
    np.testing.assert_array_equal(blocks.classes(local, off, 0, len(off) - 1), cls)
    assert blocks.seeker_off[0] == 0 and blocks.seeker_off[-1] == len(off) - 1
    assert np.all(np.diff(blocks.seeker_off) >= 0)
    for b in range(blocks.n_blocks):
        s0, s1 = blocks.seeker_off[b], blocks.seeker_off[b + 1]
        table = blocks.cls[blocks.cls_off[b] : blocks.cls_off[b + 1]]
        assert len(np.unique(table)) == len(table)  # each class once per block
        longest = int(np.diff(off)[s0:s1].max(initial=0))
        assert len(table) <= max(limit, longest)  # only a long list overflows it
        pairs = local[off[s0] : off[s1]].astype(np.int64)
        assert pairs.max(initial=-1) < len(table)
        # numbered in order of first use
        first = np.unique(pairs, return_index=True)[1]
        np.testing.assert_array_equal(np.unique(pairs), np.arange(len(table)))
        assert np.all(np.diff(first) > 0)


def test_appending_in_pieces_cuts_the_same_blocks_as_at_once():
    off, cls = random_lists(9, n_od=80)
    whole_local, whole = localize_lists(off, cls, 50, 12)
    localizer = Localizer(50, limit=12)
    lens = np.diff(off)
    for a, b in ((0, 7), (7, 8), (8, 40), (40, 80)):
        localizer.append(lens[a:b], cls[off[a] : off[b]])
    pieces = localizer.finish()
    np.testing.assert_array_equal(localizer.local(), whole_local)
    for name in ("seeker_off", "cls", "cls_off"):
        np.testing.assert_array_equal(getattr(pieces, name), getattr(whole, name))


def test_a_list_longer_than_16_bits_allow_widens_what_was_written(tmp_path, monkeypatch):
    monkeypatch.setattr(blocks_module, "NARROW_LIMIT", 5)
    off, cls = random_lists(3, n_od=30, longest=4)  # fits 16 "bits" (here: 5 classes)
    long_list = np.arange(9, dtype=np.int32)
    path = tmp_path / "local.bin"
    with open(path, "w+b") as fh:
        localizer = Localizer(50, fh, limit=5)
        first = localizer.append(np.diff(off), cls)
        assert localizer.dtype == np.uint16
        second = localizer.append(np.array([9]), long_list)
        assert localizer.dtype == np.int32
    written = np.fromfile(path, dtype="<i4")
    np.testing.assert_array_equal(written, np.concatenate([first, second]))
    blocks = localizer.finish()
    all_off = np.concatenate([off, [off[-1] + 9]])
    np.testing.assert_array_equal(
        blocks.classes(written, all_off, 0, len(all_off) - 1), np.concatenate([cls, long_list])
    )


def test_inconsistent_blocks_are_refused(tmp_path):
    ClassBlocks(seeker_off=np.array([0, 3]), cls=np.array([1, 2], np.int32), cls_off=np.array([0, 2])).save(tmp_path)
    assert ClassBlocks.load(tmp_path, 3).n_blocks == 1
    with pytest.raises(ValueError, match="inconsistent"):
        ClassBlocks.load(tmp_path, 4)
