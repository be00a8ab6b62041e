"""Damaged cache values: a changed value in any cache entry is a rebuild with one note, never a crash or a
silent use; stale temporaries of dead writers are swept, a live writer's are kept.

The seeker/taker structure is checked twice: its files' SHA-256 (once per file identity, then vouched for
by the stamp) and, on every open, every index the compiled sweeps follow.  The ``vouched`` cases forge a
consistent manifest and stamp for the damaged files, so only the index checks stand between them and a
segmentation fault.  Every test caches into its own temporary ``$RPBENCH_CACHE``.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import rpbench.files.paths as paths
import rpbench.predict.cache as predict_cache
import rpbench.predict.list_cache as list_cache
from rpbench.predict import OdRates, PredictConfig, predict
from rpbench.scenarios.base import Params
from rpbench.scenarios.toy import grid_network

from .test_inputs_helpers import cli_ok, leftovers


@pytest.fixture(autouse=True)
def cache(tmp_path: Path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("RPBENCH_CACHE", str(folder))
    new_process()
    yield folder
    new_process()


def new_process() -> None:
    """Forget what this process keeps between uses of the cache, as a new run would."""
    list_cache._RECENT.clear()
    paths._SWEPT.clear()


def inputs():
    net = grid_network(6, seed=5)
    rng = np.random.default_rng(5)
    o, d = rng.integers(0, net.n_nodes, 40), rng.integers(0, net.n_nodes, 40)
    rates = OdRates.from_arrays(
        o, d, rng.uniform(0.5, 1.5, 40) / 600.0, np.arange(40), n_nodes=net.n_nodes, source="fault test"
    )
    return net, rates, Params(max_pickup_m=3000.0, max_detour_m=3000.0), PredictConfig()


def structure(cache: Path) -> Path:
    (entry,) = (p for p in cache.glob("predict-structure-*") if p.is_dir())
    return entry


def forget_predictions(cache: Path) -> None:
    """Delete the solved predictions, so the next prediction opens the structure."""
    for p in cache.glob("predict-*.npz"):
        p.unlink()


# ------------------------------------------------------------------ damage to the structure's files
def resave_npz(path: Path, change) -> None:
    """Rewrite an ``.npz`` through ``change(dict of arrays)`` (a valid zip of the same members)."""
    with np.load(path) as z:
        members = {k: z[k].copy() for k in z.files}
    change(members)
    with open(path, "wb") as fh:
        np.savez(fh, **members)


def random_local(entry: Path) -> None:
    local = entry / "local.bin"
    local.write_bytes(np.random.default_rng(0).bytes(local.stat().st_size))


def classes_out_of_range(entry: Path) -> None:
    def change(m):
        m["cls"][len(m["cls"]) // 2] = 10**6

    resave_npz(entry / "blocks.npz", change)


def negative_class(entry: Path) -> None:
    def change(m):
        m["cls"][0] = -3

    resave_npz(entry / "blocks.npz", change)


def offsets_reordered(entry: Path) -> None:
    off = np.load(entry / "seeker_off.npy")
    off[5:15] = off[5:15][::-1].copy()
    np.save(entry / "seeker_off.npy", off)


def block_offsets_past_the_end(entry: Path) -> None:
    def change(m):
        assert len(m["seeker_off"]) == 2  # one block: the toy's lists name few classes
        m["seeker_off"][-1] += 3  # past the last seeker
        m["cls_off"][-1] += 3  # past the block classes

    resave_npz(entry / "blocks.npz", change)


def savings_scaled(entry: Path) -> None:
    def change(m):
        m["class_rest_m"] *= 1.05  # every pair's saving E moves with l(h, d_A)

    resave_npz(entry / "states.npz", change)


def state_members_out_of_range(entry: Path) -> None:
    def change(m):
        m["class_members"][-1] = len(m["class_members"]) + 99

    resave_npz(entry / "states.npz", change)


def state_offsets_reordered(entry: Path) -> None:
    def change(m):
        m["od_state_off"][3:9] = m["od_state_off"][3:9][::-1].copy()

    resave_npz(entry / "states.npz", change)


def truncate_file(name: str):
    def damage(entry: Path) -> None:
        path = entry / name
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])

    return damage


def flip_local_byte(entry: Path) -> None:
    with open(entry / "local.bin", "r+b") as fh:  # in place: size kept
        fh.seek(1)
        byte = fh.read(1)
        fh.seek(1)
        fh.write(bytes([byte[0] ^ 0x01]))


def manifest_pairs_changed(entry: Path) -> None:
    manifest = json.loads((entry / "manifest.json").read_text())
    manifest["n_pairs"] += 1
    (entry / "manifest.json").write_text(json.dumps(manifest))


STRUCTURE_DAMAGE = {
    "random bytes in local.bin": random_local,
    "one bit of local.bin flipped in place": flip_local_byte,
    "out-of-range class numbers in blocks.npz": classes_out_of_range,
    "a negative class number in blocks.npz": negative_class,
    "reordered seeker offsets": offsets_reordered,
    "block offsets past the end": block_offsets_past_the_end,
    "savings scaled by 1.05": savings_scaled,
    "state members out of range": state_members_out_of_range,
    "reordered state offsets": state_offsets_reordered,
    "local.bin truncated": truncate_file("local.bin"),
    "states.npz truncated": truncate_file("states.npz"),
    "manifest edited": manifest_pairs_changed,
    "manifest missing": lambda e: (e / "manifest.json").unlink(),
}

#: Damage that breaks an index the sweeps follow: caught even when the digests are forged to match.
INDEX_DAMAGE = (
    "random bytes in local.bin",
    "out-of-range class numbers in blocks.npz",
    "a negative class number in blocks.npz",
    "reordered seeker offsets",
    "block offsets past the end",
    "state members out of range",
    "reordered state offsets",
)


def vouch(entry: Path) -> None:
    """Forge a manifest and a stamp that match the files as they are now (what no digest can catch)."""
    manifest = json.loads((entry / "manifest.json").read_text())
    for name in list_cache.ENTRY_FILES:
        manifest["files"][name] = [(entry / name).stat().st_size, list_cache._file_digest(entry / name)]
    manifest["digest"] = list_cache._manifest_digest(manifest)
    (entry / "manifest.json").write_text(json.dumps(manifest))
    list_cache._write_stamp(entry, manifest)


def assert_same(a, b) -> None:
    np.testing.assert_array_equal(a.rho, b.rho)
    for name in ("pairing_prob", "p_seeker", "e_seeker", "e_vacant"):
        np.testing.assert_array_equal(getattr(a.od, name), getattr(b.od, name))


def structure_notes(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("rpbench: note:") and "prediction structure" in line]


@pytest.mark.parametrize(
    ("damage", "forged"),
    [(d, False) for d in STRUCTURE_DAMAGE] + [(d, True) for d in INDEX_DAMAGE],
    ids=[*STRUCTURE_DAMAGE, *(f"{d}, vouched" for d in INDEX_DAMAGE)],
)
def test_damaged_structure_is_rebuilt_with_a_note_to_the_fresh_prediction(cache, capsys, damage, forged):
    fresh = predict(*inputs(), use_cache=False)
    predict(*inputs())  # builds the structure and caches the prediction
    entry = structure(cache)
    STRUCTURE_DAMAGE[damage](entry)
    if forged:
        vouch(entry)
    forget_predictions(cache)
    new_process()
    capsys.readouterr()
    again = predict(*inputs())
    err = capsys.readouterr().err
    notes = structure_notes(err)
    assert len(notes) == 1, err
    assert notes[0].startswith("rpbench: note: the cached prediction structure predict-structure-")
    assert notes[0].endswith("; rebuilding it")
    assert_same(again, fresh)
    forget_predictions(cache)
    new_process()
    reused = predict(*inputs())  # the rebuilt entry verifies, silently
    assert structure_notes(capsys.readouterr().err) == []
    assert_same(reused, fresh)
    assert not leftovers(cache)


def test_the_note_says_which_file_and_why(cache, capsys):
    predict(*inputs())
    random_local(structure(cache))
    forget_predictions(cache)
    new_process()
    capsys.readouterr()
    predict(*inputs())
    (note,) = structure_notes(capsys.readouterr().err)
    assert "local.bin does not match its SHA-256 digest (changed on disk)" in note


def test_a_vouched_index_damage_names_the_broken_index(cache, capsys):
    predict(*inputs())
    entry = structure(cache)
    classes_out_of_range(entry)
    vouch(entry)
    forget_predictions(cache)
    new_process()
    capsys.readouterr()
    predict(*inputs())
    (note,) = structure_notes(capsys.readouterr().err)
    assert "name classes outside" in note


def test_a_verified_entry_is_not_hashed_again_until_a_file_changes(cache, capsys, monkeypatch):
    predict(*inputs())
    entry = structure(cache)
    hashed: list[str] = []
    real = list_cache._file_digest
    monkeypatch.setattr(list_cache, "_file_digest", lambda p: hashed.append(p.name) or real(p))
    forget_predictions(cache)
    new_process()
    predict(*inputs())
    assert hashed == []  # the build's stamp vouches for its files
    os.utime(entry / "blocks.npz")  # touched (same bytes): hashed once, then stamped again
    forget_predictions(cache)
    new_process()
    predict(*inputs())
    assert sorted(hashed) == sorted(list_cache.ENTRY_FILES)
    hashed.clear()
    forget_predictions(cache)
    new_process()
    predict(*inputs())
    assert hashed == [] and structure_notes(capsys.readouterr().err) == []


@pytest.mark.parametrize("stamp", ["missing", "garbage", "of other files"], ids=lambda s: s.replace(" ", "-"))
def test_a_lost_stamp_costs_a_rehash_not_a_rebuild(cache, capsys, stamp):
    fresh = predict(*inputs(), use_cache=False)
    predict(*inputs())
    path = structure(cache) / list_cache.STAMP
    if stamp == "missing":
        path.unlink()
    elif stamp == "garbage":
        path.write_bytes(b"\xff{")
    else:
        path.write_text(json.dumps({"manifest": "0" * 64, "files": {}}))
    forget_predictions(cache)
    new_process()
    capsys.readouterr()
    again = predict(*inputs())
    assert structure_notes(capsys.readouterr().err) == []
    assert_same(again, fresh)
    assert json.loads(path.read_text())["files"]  # stamped again


def test_an_entry_of_the_previous_format_is_rebuilt_and_removed(cache, capsys):
    predict(*inputs())
    entry = structure(cache)
    manifest = json.loads((entry / "manifest.json").read_text())
    old = cache / "predict-structure-oldformat"
    entry.rename(old)
    manifest["version"] = str(int(list_cache.LISTS_FORMAT_VERSION) - 1)
    for key in ("files", "digest"):
        manifest.pop(key)
    (old / "manifest.json").write_text(json.dumps(manifest))
    forget_predictions(cache)
    new_process()
    capsys.readouterr()
    predict(*inputs())
    assert "removed the outdated prediction structure predict-structure-oldformat" in capsys.readouterr().err
    assert not old.exists() and structure(cache).name != old.name


# ------------------------------------------------------------------------------ the prediction entry
def prediction_entry(cache: Path) -> Path:
    (path,) = cache.glob("predict-*.npz")
    return path


def halve(*names: str):
    def damage(path: Path) -> None:
        def change(m):
            for name in names:
                m[name] = m[name] * 0.5

        resave_npz(path, change)

    return damage


PREDICTION_DAMAGE = {
    "probabilities halved": halve("od_pairing_prob", "od_p_seeker"),
    "one per-state probability halved": halve("p_taker"),
    "savings scaled by 1.05": lambda p: resave_npz(p, lambda m: m.update(od_e_vacant=m["od_e_vacant"] * 1.05)),
    "facts changed": lambda p: resave_npz(
        p, lambda m: m.update(info_json=np.frombuffer(b'{"iterations": 1}', dtype=np.uint8))
    ),
    "truncated": lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]),
}


@pytest.mark.parametrize("slim", [False, True], ids=["full", "slim"])
@pytest.mark.parametrize("damage", PREDICTION_DAMAGE)
def test_changed_prediction_values_are_recomputed_with_a_note(cache, capsys, damage, slim):
    from rpbench.predict.prediction import cached_prediction

    fresh = predict(*inputs(), use_cache=False)
    predict(*inputs())
    path = prediction_entry(cache)
    PREDICTION_DAMAGE[damage](path)
    capsys.readouterr()
    hit = cached_prediction(*inputs(), slim=slim)
    if slim and damage == "one per-state probability halved":
        # A slim read neither reads nor uses the per-state arrays: the per-OD values it returns are intact.
        assert hit is not None
        np.testing.assert_array_equal(hit.od.pairing_prob, fresh.od.pairing_prob)
        return
    assert hit is None
    (note,) = capsys.readouterr().err.splitlines()
    assert note.startswith(f"rpbench: note: the cached prediction {path.name} ") and note.endswith("; recomputing it")
    again = predict(*inputs())
    assert not again.from_cache
    assert_same(again, fresh)
    assert predict(*inputs()).from_cache


def test_a_prediction_entry_carries_the_digest_of_every_member(cache):
    predict(*inputs())
    with np.load(prediction_entry(cache)) as z:
        manifest = json.loads(bytes(z["manifest_json"]).decode())
        members = {k: z[k] for k in z.files if k != "manifest_json"}
    assert sorted(manifest) == sorted(members)
    for name, (dtype, shape, digest) in manifest.items():
        assert (dtype, shape, digest) == (
            members[name].dtype.str,
            list(members[name].shape),
            predict_cache.member_digest(members[name]),
        )


# ----------------------------------------------------------------------------- a whole FL run (CLI)
TOY_FL = ("run", "--scenario", "toy", "--sample", "0.1", "--strategies", "fl", "--no-progress")
TIMING = ("decision_p50_s", "decision_p95_s", "decision_max_s", "wall_s")


def fl_results(capsys, out: Path) -> tuple[str, str, str]:
    _, err = cli_ok(capsys, *TOY_FL, "--out", out)
    kpis = "".join(line for line in (out / "kpis.csv").open() if not any(f",{t}," in line for t in TIMING))
    return (out / "table.csv").read_text(), kpis, err


def damage_apsp(cache: Path) -> None:
    (dist,) = cache.glob("apsp-*-dist.npy")
    a = np.load(dist)
    a[1, 2] *= 0.5
    np.save(dist, a)


CLI_DAMAGE = {
    "random bytes in local.bin": (lambda c: random_local(structure(c)), "prediction structure"),
    "out-of-range classes, vouched": (
        lambda c: (classes_out_of_range(structure(c)), vouch(structure(c))),
        "prediction structure",
    ),
    "halved probabilities": (lambda c: halve("od_pairing_prob", "od_p_seeker")(prediction_entry(c)), "prediction"),
    "all-pairs digest mismatch": (damage_apsp, "all-pairs distances"),
}


@pytest.mark.parametrize("damage", CLI_DAMAGE)
def test_an_fl_run_on_a_damaged_cache_rebuilds_it_and_gives_the_fresh_results(cache, tmp_path, capsys, damage):
    fresh_table, fresh_kpis, _ = fl_results(capsys, tmp_path / "fresh")
    change, what = CLI_DAMAGE[damage]
    change(cache)
    if what == "prediction structure":
        forget_predictions(cache)  # FL solves again, on the structure
    new_process()
    table, kpis, err = fl_results(capsys, tmp_path / "again")
    notes = [line for line in err.splitlines() if line.startswith("rpbench: note:")]
    assert len(notes) == 1 and f"cached {what}" in notes[0], err
    assert (table, kpis) == (fresh_table, fresh_kpis)


# --------------------------------------------------------------------------- stale temporary entries
def dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def make_old(path: Path, age_s: float) -> None:
    when = time.time() - age_s
    for p in [*path.iterdir(), path] if path.is_dir() else [path]:
        os.utime(p, (when, when))


def partial_structure(cache: Path, pid: int, age_s: float) -> Path:
    cache.mkdir(parents=True, exist_ok=True)
    tmp = cache / f".predict-structure-0123456789abcdef01234567.k2j4x9q1.{pid}.tmp"
    tmp.mkdir()
    (tmp / "local.bin").write_bytes(b"\0" * 4096)
    make_old(tmp, age_s)
    return tmp


def partial_file(cache: Path, name: str, pid: int, age_s: float) -> Path:
    cache.mkdir(parents=True, exist_ok=True)
    tmp = cache / f".{name}.{pid}.tmp"
    tmp.write_bytes(b"\0" * 100)
    make_old(tmp, age_s)
    return tmp


OLD = 2 * paths.STALE_AFTER_S


def test_stale_temporaries_of_dead_writers_are_swept_with_a_note(cache, capsys):
    pid = dead_pid()
    stale = [
        partial_structure(cache, pid, OLD),
        partial_file(cache, "predict-0123456789abcdef01234567.npz", pid, OLD),
        partial_file(cache, "apsp-0123456789abcdef0123-dist.npy", pid, OLD),
    ]
    paths.cache_dir()
    err = capsys.readouterr().err.splitlines()
    assert not any(p.exists() for p in stale)
    assert len(err) == 3 and all(
        line.startswith("rpbench: note: removed the stale temporary cache entry") for line in err
    )
    assert all(f"left by process {pid}, which no longer runs" in line for line in err)
    assert not [p for p in cache.iterdir() if p.name.startswith(".")]  # nor their claimed names


def test_a_live_writers_temporary_is_kept(cache, capsys):
    writer = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        kept = [
            partial_structure(cache, writer.pid, OLD),
            partial_file(cache, "predict-0123456789abcdef01234567.npz", writer.pid, OLD),
            partial_file(cache, "apsp-0123456789abcdef0123-pred.npy", os.getpid(), OLD),  # this process's own
        ]
        paths.cache_dir()
        assert all(p.exists() for p in kept)
        assert capsys.readouterr().err == ""
    finally:
        writer.kill()
        writer.wait()


def test_a_dead_writers_recent_temporary_is_kept(cache, capsys):
    recent = partial_structure(cache, dead_pid(), paths.STALE_AFTER_S / 2)
    paths.cache_dir()
    assert recent.exists() and capsys.readouterr().err == ""


def test_temporaries_without_a_pid_only_when_a_day_old_and_other_files_never(cache, capsys):
    cache.mkdir(parents=True)
    legacy_old, legacy_new = (cache / f".predict-structure-0123456789abcdef01234567.{r}" for r in ("a1b2c3", "d4e5f6"))
    for folder, age in ((legacy_old, 2 * paths.LEGACY_STALE_AFTER_S), (legacy_new, OLD)):
        folder.mkdir()
        (folder / "local.bin").write_bytes(b"x")
        make_old(folder, age)
    others = [cache / ".hidden-notes.tmp", cache / ".keep", cache / "predict-structure-0123.lock"]
    for p in others:
        p.write_text("x")
        make_old(p, 2 * paths.LEGACY_STALE_AFTER_S)
    paths.cache_dir()
    assert not legacy_old.exists() and legacy_new.exists() and all(p.exists() for p in others)
    (note,) = capsys.readouterr().err.splitlines()
    assert legacy_old.name in note and "an older rpbench" in note


def test_a_killed_build_leaves_a_temporary_that_a_later_run_sweeps(cache, tmp_path, capsys):
    """SIGKILL mid-build: the hidden folder stays (nothing can clean up), the next use removes it."""
    net, rates, params, config = inputs()
    script = (
        "import os, signal, rpbench.predict.list_cache as lc\n"
        "from rpbench.predict import match_sets\n"
        "real = match_sets.build_matching\n"
        "def killed(*a, **kw):\n"
        "    real(*a, **kw)\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"
        "lc.build_matching = killed\n"
        f"import sys; sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r})\n"
        "from faults.test_caches_values import inputs\n"
        "lc.load_lists(*inputs())\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE, text=True)
    _, err = child.communicate(timeout=300)
    assert child.returncode == -signal.SIGKILL, err
    (tmp,) = [p for p in cache.iterdir() if p.name.startswith(".predict-structure-")]
    assert tmp.name.endswith(f".{child.pid}.tmp") and (tmp / "local.bin").stat().st_size > 0
    paths.cache_dir()
    assert tmp.exists()  # too recent: the pid alone is not trusted
    make_old(tmp, OLD)
    new_process()
    capsys.readouterr()
    fresh = predict(net, rates, params, config, use_cache=False)
    again = predict(net, rates, params, config)
    err = capsys.readouterr().err
    assert not tmp.exists() and f"removed the stale temporary cache entry {tmp.name}" in err
    assert_same(again, fresh)
