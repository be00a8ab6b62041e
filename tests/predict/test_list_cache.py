"""The seeker/taker structure in the disk cache (:class:`CachedLists`): key, reuse, repair, private builds, lock."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import rpbench.predict.list_cache as list_cache
from rpbench.predict.rates import OdRates

from .conftest import make_instance


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("RPBENCH_CACHE", str(folder))
    list_cache._RECENT.clear()
    yield folder
    list_cache._RECENT.clear()


def load(inst, **config):
    return list_cache.load_lists(inst.network, inst.rates, inst.params, inst.config.replace(**config))


def entries(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("predict-structure-*") if p.is_dir())


def test_key_follows_the_structure_inputs_only():
    inst = make_instance(seed=1)
    key = list_cache.lists_key(inst.network, inst.rates, inst.params, inst.config)
    same = [
        (inst.rates.scaled(3.0), inst.params, inst.config.replace(tau0_s=77.0, beta=0.25, tol=1e-8)),
        (inst.rates, inst.params.replace(response_rate=0.5), inst.config.replace(accel="anderson")),
    ]
    for rates, params, config in same:
        assert list_cache.lists_key(inst.network, rates, params, config) == key
    other_ods = OdRates.from_arrays(
        inst.rates.origin[1:], inst.rates.destination[1:], inst.rates.rate_per_s[1:], n_nodes=inst.network.n_nodes
    )
    changed = [
        (other_ods, inst.params, inst.config),
        (inst.rates, inst.params.replace(max_pickup_m=999.0), inst.config),
        (inst.rates, inst.params.replace(speed_mps=9.0), inst.config),
        (inst.rates, inst.params, inst.config.replace(priority="pickup")),
        (inst.rates, inst.params, inst.config.replace(include_origin_state=False)),
    ]
    keys = {list_cache.lists_key(inst.network, r, p, c) for r, p, c in changed}
    assert key not in keys and len(keys) == len(changed)


def test_built_once_then_mapped_from_the_cache(cache):
    inst = make_instance(seed=2, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    first = load(inst)
    assert first.build_s["matching_s"] > 0 and entries(cache) == [first.directory]
    list_cache._RECENT.clear()  # a new process: reopened from disk
    again = load(inst, tau0_s=300.0)
    assert again.build_s["matching_s"] == 0 and again.directory == first.directory
    assert isinstance(again.matching.local, np.memmap) and again.matching.local.dtype == np.uint16
    for a, b in zip(again.matching.arrays(), first.matching.arrays(), strict=True):
        np.testing.assert_array_equal(a, b)
    sp = again.space_for(300.0)
    np.testing.assert_array_equal(sp.tau_s[sp.k == 0], 300.0)
    np.testing.assert_array_equal(sp.tau_s[sp.k > 0], first.space.tau_s[first.space.k > 0])


def test_an_entry_holds_the_class_lists_and_the_states_only(cache):
    inst = make_instance(seed=2, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    lists = load(inst)
    assert sorted(p.name for p in lists.directory.iterdir()) == [
        "blocks.npz",
        "local.bin",
        "manifest.json",
        "seeker_off.npy",
        "states.npz",
        "verified.json",
    ]
    assert (lists.directory / "local.bin").stat().st_size == 2 * lists.matching.n_pairs
    manifest = json.loads((lists.directory / "manifest.json").read_text())
    assert manifest["version"] == list_cache.LISTS_FORMAT_VERSION and manifest["local"] == "<u2"
    local = lists.directory / "local.bin"
    assert manifest["files"]["local.bin"] == [local.stat().st_size, hashlib.sha256(local.read_bytes()).hexdigest()]


def test_a_build_announces_what_where_and_its_size_in_one_line_and_nothing_else(cache, capsys):
    """stderr is not a terminal here: no progress bar, only the announcing line."""
    inst = make_instance(seed=2, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    load(inst)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1, err
    assert f"building the seeker/taker prediction structure for {len(inst.rates)} OD pairs" in err[0]
    assert f"in {cache}, about 1 MB on disk" in err[0]


def test_the_announced_size_comes_from_a_sample_of_the_lists():
    from rpbench.predict.match_sets import _Builder

    inst = make_instance(seed=7, size=7, n_od=120, max_pickup_m=3000, max_detour_m=3000)
    lists = list_cache.load_lists(inst.network, inst.rates, inst.params, inst.config, use_cache=False)
    dist = inst.network.distances().dist
    builder = _Builder(lists.space, inst.rates, dist, inst.params, inst.config)
    assert builder.sample_pairs(samples=len(inst.rates)) == lists.matching.n_pairs  # every seeker sampled
    assert 0.5 < builder.sample_pairs() / lists.matching.n_pairs < 2.0  # 64 of 120


def test_a_damaged_entry_is_rebuilt_with_a_note(cache, capsys):
    inst = make_instance(seed=3, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    good = load(inst).matching.arrays()
    entry = entries(cache)[0]
    with open(entry / "local.bin", "r+b") as fh:
        fh.truncate(8)
    list_cache._RECENT.clear()
    rebuilt = load(inst)
    assert "unusable" in capsys.readouterr().err
    assert rebuilt.build_s["matching_s"] > 0
    for a, b in zip(rebuilt.matching.arrays(), good, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", ["blocks.npz", "states.npz", "seeker_off.npy"])
def test_a_truncated_array_file_is_rebuilt_with_a_note(cache, capsys, name):
    inst = make_instance(seed=3, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    good = load(inst).matching.arrays()
    path = entries(cache)[0] / name
    path.write_bytes(path.read_bytes()[:100])
    list_cache._RECENT.clear()
    rebuilt = load(inst)
    assert "unusable" in capsys.readouterr().err
    for a, b in zip(rebuilt.matching.arrays(), good, strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_build_removes_entries_of_older_formats_only(cache, capsys):
    old, newer, odd = (cache / f"predict-structure-{name}" for name in ("old", "newer", "odd"))
    for entry, version in ((old, "1"), (newer, str(int(list_cache.LISTS_FORMAT_VERSION) + 1)), (odd, None)):
        entry.mkdir(parents=True)
        (entry / "cls.bin").write_bytes(b"x" * 10)
        if version is not None:
            (entry / "manifest.json").write_text(json.dumps({"version": version}))
    load(make_instance(seed=4))
    assert not old.exists() and newer.exists() and odd.exists()
    assert "removed the outdated prediction structure predict-structure-old" in capsys.readouterr().err


def test_a_private_build_leaves_nothing_behind(cache):
    inst = make_instance(seed=4)
    s = list_cache.load_lists(inst.network, inst.rates, inst.params, inst.config, use_cache=False)
    assert s.directory is None and s.matching.n_pairs > 0
    assert not [p for p in cache.glob("*structure*") if p.is_dir()]


BUILDER = """
import sys
import rpbench.predict.list_cache as list_cache
sys.path.insert(0, {tests!r})
from predict.conftest import make_instance
inst = make_instance(seed=5, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
s = list_cache.load_lists(inst.network, inst.rates, inst.params, inst.config)
print("built" if s.build_s["matching_s"] > 0 else "reused", s.matching.n_pairs)
"""


def test_a_second_builder_waits_for_the_first_and_reuses_its_entry(cache):
    inst = make_instance(seed=5, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    key = list_cache.lists_key(inst.network, inst.rates, inst.params, inst.config)
    cache.mkdir(parents=True, exist_ok=True)
    tests = str(Path(__file__).resolve().parents[1])
    with open(cache / f"predict-structure-{key}.lock", "a+") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # we are "the first builder"
        other = subprocess.Popen(
            [sys.executable, "-c", BUILDER.format(tests=tests)],
            env=dict(os.environ),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        note = other.stderr.readline()  # it finds the lock held and says so
        assert "waiting" in note
        time.sleep(0.2)
        assert other.poll() is None  # and waits
        tmp = cache / ".manual"
        tmp.mkdir()
        mine = list_cache._build_into(tmp, inst.network, inst.rates, inst.params, inst.config)
        os.replace(tmp, cache / f"predict-structure-{key}")
        fcntl.flock(lock, fcntl.LOCK_UN)
    out, err = other.communicate(timeout=120)
    assert other.returncode == 0, err
    assert out.split() == ["reused", str(mine.matching.n_pairs)]


def test_a_failed_build_leaves_no_half_entry_and_says_so_in_one_line(cache, monkeypatch):
    import errno

    from rpbench.exceptions import CacheError

    inst = make_instance(seed=6)

    def disk_full(directory, *args):
        (directory / "local.bin").write_bytes(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(list_cache, "_build_into", disk_full)
    with pytest.raises(CacheError, match="No space left on device"):
        load(inst)
    assert not [p for p in cache.iterdir() if p.is_dir()]  # neither the entry nor its temporary folder
