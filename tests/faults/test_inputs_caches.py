"""Damaged caches: a tampered or corrupt cache entry is rebuilt to the fresh result; an unusable cache
folder is one line naming it.

Every test caches into its own temporary ``$RPBENCH_CACHE`` (never the user cache).
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import threading
import zipfile
from pathlib import Path

import numpy as np
import pytest

import rpbench.predict.cache as predict_cache
from rpbench.exceptions import CacheError
from rpbench.network import Distances, apsp_digest
from rpbench.predict import OdRates, PredictConfig, predict
from rpbench.scenarios.base import Params
from rpbench.scenarios.toy import grid_network

from .test_inputs_helpers import cli_error, cli_ok, flip_byte, leftovers, scenario_json, truncate


@pytest.fixture(autouse=True)
def cache(tmp_path: Path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("RPBENCH_CACHE", str(folder))
    return folder


# ----------------------------------------------------------- all-pairs distance cache
def entries(cache: Path, pattern: str) -> list[Path]:
    """The cache's files matching ``pattern``, but its builders' lock files: empty, kept on purpose (deleting
    one a waiting process has opened would let a third process build beside it)."""
    return [p for p in cache.glob(pattern) if p.suffix != ".lock"]


def apsp_files(cache: Path) -> dict[str, Path]:
    (dist,) = cache.glob("apsp-*-dist.npy")
    stem = dist.name.removesuffix("-dist.npy")
    return {"dist": dist, "pred": cache / f"{stem}-pred.npy", "digest": cache / f"{stem}.sha256"}


def resave(path: Path, change) -> None:
    """Rewrite a cached array through ``change(array) -> array`` (same file name)."""
    array = np.load(path)
    np.save(path, change(array.copy()))


def bump(a: np.ndarray) -> np.ndarray:
    a[1, 2] += 1  # one distance (or predecessor) off by one: same shape, same dtype
    return a


def shorten(a: np.ndarray) -> np.ndarray:
    a[0, -1] = a[0, 1]  # a plausible but wrong (too short) distance
    return a


def matching_digest_for(files: dict[str, Path], dist: np.ndarray, pred: np.ndarray) -> None:
    """Replace the arrays and their digest consistently (the shape/dtype check must catch them)."""
    np.save(files["dist"], dist)
    np.save(files["pred"], pred)
    files["digest"].write_text(apsp_digest(dist, pred) + "\n")


APSP_DAMAGE = {
    "distance value changed": lambda f: resave(f["dist"], bump),
    "distance made too short": lambda f: resave(f["dist"], shorten),
    "predecessor changed": lambda f: resave(f["pred"], bump),
    "digest missing": lambda f: f["digest"].unlink(),
    "digest garbage": lambda f: f["digest"].write_bytes(b"\xff\xfe not a digest"),
    "digest of other arrays": lambda f: f["digest"].write_text(
        apsp_digest(np.zeros((2, 2)), np.zeros((2, 2), np.int32))
    ),
    "distance file truncated": lambda f: truncate(f["dist"]),
    "distance file empty": lambda f: f["dist"].write_bytes(b""),
    "distance file not npy": lambda f: f["dist"].write_text("dist,pred\n1,2\n"),
    "predecessor file missing": lambda f: f["pred"].unlink(),
    "distance file missing": lambda f: f["dist"].unlink(),
    "float32 distances with a matching digest": lambda f: matching_digest_for(
        f, np.load(f["dist"]).astype(np.float32), np.load(f["pred"])
    ),
    "wrong shape with a matching digest": lambda f: matching_digest_for(
        f, np.load(f["dist"])[:3, :3].copy(), np.load(f["pred"])[:3, :3].copy()
    ),
}


@pytest.mark.parametrize("damage", APSP_DAMAGE)
def test_damaged_distance_cache_is_rebuilt_to_the_fresh_table(cache, capsys, damage):
    fresh = Distances.build(grid_network(5))
    assert not Distances.load_or_build(grid_network(5)).from_cache  # writes the cache
    APSP_DAMAGE[damage](apsp_files(cache))
    rebuilt = Distances.load_or_build(grid_network(5))
    assert not rebuilt.from_cache
    assert np.array_equal(rebuilt.dist, fresh.dist) and np.array_equal(rebuilt.pred, fresh.pred)
    notes = capsys.readouterr().err.splitlines()
    assert len(notes) == 1 and notes[0].startswith("rpbench: note:") and "rebuilding" in notes[0]
    again = Distances.load_or_build(grid_network(5))  # the rebuilt cache verifies
    assert again.from_cache and np.array_equal(again.dist, fresh.dist)
    assert not leftovers(cache)


def test_a_table_another_process_is_writing_is_waited_for_not_rebuilt(cache, capsys):
    """A parallel sweep's workers build the same table: one that finds the arrays renamed into place but not
    yet their digest waits for the writer's lock and loads its table, with no "rebuilding" note."""
    network = grid_network(5)
    fresh = Distances.build(network)
    cache.mkdir()
    stem = cache / f"apsp-{network.content_hash}"
    np.save(f"{stem}-dist.npy", fresh.dist)
    np.save(f"{stem}-pred.npy", fresh.pred)
    loaded: list[Distances] = []
    with open(f"{stem}.lock", "a+") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # we are the writer, between the arrays and the digest
        reader = threading.Thread(target=lambda: loaded.append(Distances.load_or_build(network)))
        reader.start()
        reader.join(timeout=1.0)
        assert reader.is_alive()  # it waits for the lock
        Path(f"{stem}.sha256").write_text(apsp_digest(fresh.dist, fresh.pred) + "\n")
        fcntl.flock(lock, fcntl.LOCK_UN)
    reader.join(timeout=60)
    [oracle] = loaded
    assert oracle.from_cache and np.array_equal(oracle.dist, fresh.dist)
    assert capsys.readouterr().err == ""  # waiting is no fault of the cache


def test_first_build_writes_a_digest_and_no_note(cache, capsys):
    oracle = Distances.load_or_build(grid_network(4))
    files = apsp_files(cache)
    assert files["digest"].read_text().strip() == apsp_digest(oracle.dist, oracle.pred)
    assert capsys.readouterr().err == ""


def test_tampered_distance_cache_gives_the_fresh_scenario_summary(cache, capsys):
    fresh = scenario_json(capsys, "toy", "--sample", "0.2")
    resave(apsp_files(cache)["dist"], lambda a: a * 0.5)  # every distance halved
    rebuilt = scenario_json(capsys, "toy", "--sample", "0.2")
    assert rebuilt == fresh


# ------------------------------------------------------------------ the cache folder
def test_cache_path_is_a_file(cache, capsys):
    cache.write_text("not a folder")
    line = cli_error(capsys, "scenario", "toy", "--json")
    assert "$RPBENCH_CACHE" in line and str(cache) in line and "cannot be created" in line


def test_cache_path_below_a_file(cache, capsys, monkeypatch):
    cache.write_text("not a folder")
    monkeypatch.setenv("RPBENCH_CACHE", str(cache / "sub"))
    line = cli_error(capsys, "scenario", "toy", "--json")
    assert "$RPBENCH_CACHE" in line and str(cache / "sub") in line


def test_cache_path_that_cannot_be_created(capsys, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", "/proc/rpbench-no-such-cache")
    line = cli_error(capsys, "scenario", "toy", "--json")
    assert "$RPBENCH_CACHE" in line and "/proc/rpbench-no-such-cache" in line


def test_read_only_cache_folder(cache, capsys, monkeypatch):
    cache.mkdir()
    cache.chmod(0o500)
    if os.geteuid() == 0:  # root may write anyway: let access() answer as it would for a user
        real_access = os.access
        monkeypatch.setattr(os, "access", lambda p, mode, **kw: Path(p) != cache and real_access(p, mode, **kw))
    try:
        line = cli_error(capsys, "scenario", "toy", "--json")
    finally:
        cache.chmod(0o700)
    assert "not writable" in line and "$RPBENCH_CACHE" in line


def test_disk_full_while_writing_the_distance_cache(cache, capsys, monkeypatch):
    real_save = np.save

    def save_then_fail(fh, array, *a, **kw):
        real_save(fh, array[: len(array) // 2], *a, **kw)  # half the bytes, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "save", save_then_fail)
    line = cli_error(capsys, "scenario", "toy", "--json")
    assert "cannot write the cache file" in line and "No space left on device" in line
    assert not leftovers(cache) and not entries(cache, "apsp-*")  # nothing half-written
    monkeypatch.setattr(np, "save", real_save)
    cli_ok(capsys, "scenario", "toy", "--json")  # and the next run works


# -------------------------------------------------------------------- prediction cache
def small_prediction_inputs():
    net = grid_network(4, seed=3)
    rng = np.random.default_rng(3)
    o, d = rng.integers(0, net.n_nodes, 8), rng.integers(0, net.n_nodes, 8)
    rates = OdRates.from_arrays(
        o, d, rng.uniform(0.5, 1.5, 8) / 600.0, np.arange(8), n_nodes=net.n_nodes, source="fault test"
    )
    return net, rates, Params(max_pickup_m=1500.0, max_detour_m=1500.0), PredictConfig()


def entry_path(inputs) -> Path:
    return predict_cache.cache_path(predict_cache.cache_key(*inputs))


def rewrite_entry(path: Path, change) -> None:
    """Rewrite a cache entry's members through ``change(dict of arrays) -> dict`` (a valid zip again)."""
    with np.load(path) as z:
        members = {k: z[k] for k in z.files}
    with open(path, "wb") as fh:
        np.savez(fh, **change(members))


def without(name: str):
    return lambda m: {k: v for k, v in m.items() if k != name}


def replaced(name: str, value):
    return lambda m: {**m, name: value}


def json_member(obj) -> np.ndarray:
    return np.frombuffer(json.dumps(obj).encode(), dtype=np.uint8)


def first_member_data_offset(path: Path) -> int:
    with zipfile.ZipFile(path) as zf:
        info = zf.infolist()[0]
    return info.header_offset + 30 + len(info.filename.encode()) + len(info.extra) + 40


def pickled_member(path: Path) -> None:
    with np.load(path) as z:
        members = {k: z[k] for k in z.files}
    members["od_p_seeker"] = np.array([object()] * len(members["od_p_seeker"]), dtype=object)
    with open(path, "wb") as fh:
        np.savez(fh, **members)


def short_member(path: Path) -> None:
    """A valid zip whose ``rho.npy`` member holds only half the bytes its header declares."""
    with zipfile.ZipFile(path) as zf:
        members = {info.filename: zf.read(info) for info in zf.infolist()}
    members["rho.npy"] = members["rho.npy"][: 128 + (len(members["rho.npy"]) - 128) // 2]
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)


PREDICT_DAMAGE = {
    "truncated": lambda p: truncate(p, 0.6),
    "an array's data cut short (valid zip)": short_member,
    "cut to its first bytes": lambda p: truncate(p, 0.01),
    "empty file": lambda p: p.write_bytes(b""),
    "not a zip": lambda p: p.write_text("predictions,were,here\n"),
    "a data byte flipped (CRC)": lambda p: flip_byte(p, first_member_data_offset(p)),
    "zip directory damaged": lambda p: flip_byte(p, -10),
    "an array missing": lambda p: rewrite_entry(p, without("rho")),
    "an array of the wrong shape": lambda p: rewrite_entry(p, replaced("eta", np.zeros(3))),
    "facts missing": lambda p: rewrite_entry(p, without("info_json")),
    "facts not JSON": lambda p: rewrite_entry(p, replaced("info_json", np.frombuffer(b"{oops", np.uint8))),
    "facts not an object": lambda p: rewrite_entry(p, replaced("info_json", json_member([1, 2]))),
    "manifest not an object": lambda p: rewrite_entry(p, replaced("manifest_json", json_member("x"))),
    "an object array (pickle)": pickled_member,
    "another number of ODs": lambda p: rewrite_entry(p, replaced("od_p_seeker", np.zeros(3))),
}


@pytest.mark.parametrize("damage", PREDICT_DAMAGE)
def test_damaged_prediction_cache_is_deleted_and_recomputed(cache, capsys, damage):
    inputs = small_prediction_inputs()
    fresh = predict(*inputs, use_cache=False)
    assert not predict(*inputs).from_cache  # writes the entry
    path = entry_path(inputs)
    PREDICT_DAMAGE[damage](path)
    again = predict(*inputs)
    assert not again.from_cache
    np.testing.assert_array_equal(again.od.pairing_prob, fresh.od.pairing_prob)
    np.testing.assert_array_equal(again.rho, fresh.rho)
    notes = [line for line in capsys.readouterr().err.splitlines() if "cached prediction" in line]
    assert len(notes) == 1 and "recomputing" in notes[0]
    hit = predict(*inputs)  # rewritten, readable again
    assert hit.from_cache
    np.testing.assert_array_equal(hit.od.pairing_prob, fresh.od.pairing_prob)
    assert not leftovers(cache)


def old_manifest(members: dict) -> dict:
    """The manifest an older rpbench wrote: dtype and shape of each array, no digest."""
    arrays = {k: v for k, v in members.items() if not k.endswith("_json")}
    return {**members, "manifest_json": json_member({k: [v.dtype.str, list(v.shape)] for k, v in arrays.items()})}


@pytest.mark.parametrize("change", [without("manifest_json"), old_manifest], ids=["no manifest", "no digests"])
def test_prediction_entry_without_digests_is_recomputed_once(cache, capsys, change):
    inputs = small_prediction_inputs()
    first = predict(*inputs)
    rewrite_entry(entry_path(inputs), change)
    again = predict(*inputs)
    assert not again.from_cache
    notes = capsys.readouterr().err.splitlines()
    assert len(notes) == 1 and "has no content digests (written by an older rpbench); recomputing" in notes[0]
    np.testing.assert_array_equal(again.od.pairing_prob, first.od.pairing_prob)
    hit = predict(*inputs)
    assert hit.from_cache and capsys.readouterr().err == ""


def test_disk_full_while_writing_a_prediction(cache, monkeypatch):
    inputs = small_prediction_inputs()
    Distances.load_or_build(inputs[0])  # the distances are cached already

    def fail(*a, **kw):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savez", fail)
    with pytest.raises(CacheError, match="cannot write the cache file .*predict-.*No space left"):
        predict(*inputs)
    assert not leftovers(cache) and not entries(cache, "predict-*")
