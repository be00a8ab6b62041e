"""The seeker/taker structure (:class:`CachedLists`): the τ_0-independent part of the prediction, built once
per machine and shared through the disk cache.

The taker states (:mod:`.states`) and the seekers' sorted matching lists
(:mod:`.match_sets`) depend on the network, the OD set, R̄, D̄, v and the
priority rule, but not on the demand level λ_w nor on τ_0: those enter the
fixed point only.  For the 21-day month table the lists hold 282 M pairs
(0.67 GB with the states), so they are built once and kept in the cache
folder as raw files that every later run, τ_0, day of a multi-day run, sweep
point and worker process maps read-only (one copy in the page cache for all
of them).

Layout of ``<cache>/predict-structure-<key>/``: ``states.npz`` (the
:class:`~.states.StateSpace` with τ_0 = 0 in the origin states),
``seeker_off.npy``, ``local.bin`` (each pair's class as a block-local number,
with ``blocks.npz``: see :mod:`.blocks`; a pair's distances are recomputed
from the distance matrix, see :mod:`.match_sets`), ``manifest.json``
(sizes, the local numbers' dtype, build facts, each file's size and SHA-256,
and the manifest's own SHA-256) and ``verified.json`` (the stamp: the size,
mtime, ctime and inode of each file when its digest last matched).  An entry
is built in a temporary folder beside it (its name carries the builder's pid,
so :func:`rpbench.files.paths.sweep_stale_temporaries` removes a killed build's)
and renamed into place, so it is complete or absent; concurrent builders
take an exclusive lock on ``predict-structure-<key>.lock``, and the losers
wait and then reuse the winner's entry.

Opening an entry re-hashes its files only when the stamp no longer matches
them (about 0.7 GB for the month table: the build stamps its entry, so that
is after a file was changed or copied); every open checks the manifest's
digest, the file sizes and, cheaply, every index the compiled sweeps follow
(offsets monotone and ending at the array lengths, class numbers and local
numbers in range), so damaged values are never a crash.  A damaged entry is
deleted and rebuilt, with one note.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import hashlib
import json
import os
import shutil
import sys
import tempfile
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rpbench.exceptions import one_line
from rpbench.files.paths import builder_lock, cache_dir, cache_write_error, temporary_folder
from rpbench.network import RoadNetwork
from rpbench.predict.config import PredictConfig
from rpbench.predict.match_sets import ListGeometry, Matching, build_matching
from rpbench.predict.rates import OdRates
from rpbench.predict.states import StateSpace, build_states
from rpbench.scenarios.base import Params

#: Bump when the files, or the states or lists they hold for the same inputs, change.
LISTS_FORMAT_VERSION = "5"  # 5: file digests in the manifest, the verified stamp
#: The network-side parameters and the configuration fields the structure depends on.
KEY_PARAMS = ("max_pickup_m", "max_detour_m", "speed_mps")
KEY_CONFIG = ("include_origin_state", "priority", "keep_nonpositive", "order_rule")

#: The structure this process used last (one: the month table's maps 0.6 GB of class lists when swept),
#: so the hours of a day and the points of a sweep do not reopen it.
_RECENT: dict[str, CachedLists] = {}


@dataclass(frozen=True, eq=False)
class CachedLists:
    """States (τ_0 = 0 in the origin states) and matching lists; the lists are usually memory maps."""

    space: StateSpace
    matching: Matching
    build_s: dict  # seconds per build stage (zero when loaded from the cache)
    directory: Path | None  # the cache entry (None: a private build, already unlinked)

    def space_for(self, tau0_s: float) -> StateSpace:
        """The states with the origin states' sojourn set to ``tau0_s`` (A4)."""
        sp = self.space
        return dataclasses.replace(sp, tau_s=np.where(sp.k == 0, float(tau0_s), sp.tau_s))


def lists_key(network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig) -> str:
    """Hash of everything the structure depends on (not λ_w, not τ_0)."""
    h = hashlib.sha256()
    h.update(f"structure|{LISTS_FORMAT_VERSION}|{network.content_hash}|".encode())
    for arr in (rates.origin, rates.destination):
        h.update(np.ascontiguousarray(arr, dtype=np.int64).tobytes())
    h.update(json.dumps({k: float(getattr(params, k)) for k in KEY_PARAMS}, sort_keys=True).encode())
    h.update(json.dumps({k: getattr(config, k) for k in KEY_CONFIG}, sort_keys=True).encode())
    return h.hexdigest()[:24]


def load_lists(
    network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig, *, use_cache: bool = True
) -> CachedLists:
    """The structure for these inputs: from the cache, else built (into the cache when ``use_cache``)."""
    if not use_cache:
        return _private_build(network, rates, params, config)
    root = cache_dir()
    key = lists_key(network, rates, params, config)
    final = root / f"predict-structure-{key}"
    recent = _RECENT.get(key)
    if recent is not None and recent.directory is not None and recent.directory.is_dir():
        return recent
    _RECENT.clear()
    found = _open_entry(final, network, rates, params, config)
    if found is not None:
        _RECENT[key] = found
        return found
    waiting = f"rpbench: another process is building the prediction structure for {len(rates):,} ODs; waiting for it"
    with builder_lock(root / f"predict-structure-{key}.lock", waiting):
        found = _open_entry(final, network, rates, params, config)  # another process may have finished it meanwhile
        if found is not None:
            return found
        tmp = temporary_folder(final)

        def announce(size: int) -> None:
            print(
                f"rpbench: building the seeker/taker prediction structure for {len(rates):,} OD pairs "
                f"({rates.source}) in {root}, {_about(size)} on disk; once per machine, later runs reuse it",
                file=sys.stderr,
            )

        try:
            structure = _build_into(tmp, network, rates, params, config, announce)
            os.replace(tmp, final)
        except BaseException as exc:  # disk full, Ctrl-C: no half entry left behind
            shutil.rmtree(tmp, ignore_errors=True)
            if isinstance(exc, OSError) and not isinstance(exc, FileNotFoundError):
                raise cache_write_error(final, exc) from None
            raise
    _remove_outdated(root)
    _RECENT[key] = dataclasses.replace(structure, directory=final)
    return _RECENT[key]


def _remove_outdated(root: Path) -> None:
    """Delete cache entries written by an older structure format (up to several GB each that no version
    of this code reads again); entries of a newer format, or without a readable manifest, are left alone."""
    for entry in root.glob("predict-structure-*"):
        try:
            version = json.loads((entry / "manifest.json").read_text()).get("version")
            outdated = int(version) < int(LISTS_FORMAT_VERSION)
        except (OSError, ValueError, TypeError, AttributeError):
            continue
        if outdated:
            size = sum(f.stat().st_size for f in entry.iterdir() if f.is_file())
            shutil.rmtree(entry, ignore_errors=True)
            print(
                f"rpbench: removed the outdated prediction structure {entry.name} "
                f"(format {version}, {size / 1e9:.1f} GB) from the cache",
                file=sys.stderr,
            )


def _private_build(network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig) -> CachedLists:
    """A build for this process only: the files are unlinked at once (the maps keep them alive)."""
    try:
        tmp = temporary_folder(cache_dir() / "predict-structure-private")
    except OSError:
        tmp = Path(tempfile.mkdtemp(prefix="rpbench-structure-"))

    def announce(size: int) -> None:
        print(
            f"rpbench: building the seeker/taker prediction structure for {len(rates):,} OD pairs "
            f"({rates.source}) for this process only, {_about(size)} in {tmp.parent}, removed at exit",
            file=sys.stderr,
        )

    try:
        return dataclasses.replace(_build_into(tmp, network, rates, params, config, announce), directory=None)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _about(size: int) -> str:
    """``about 0.7 GB`` (``about 12 MB`` below a tenth of a gigabyte)."""
    return f"about {size / 1e9:.1f} GB" if size >= 1e8 else f"about {max(1, round(size / 1e6))} MB"


def _build_into(
    directory: Path,
    network: RoadNetwork,
    rates: OdRates,
    params: Params,
    config: PredictConfig,
    announce: Callable[[int], None] | None = None,
) -> CachedLists:
    """Build the entry's files in ``directory``; ``announce`` gets the estimated bytes before the lists are built."""
    t0 = time.perf_counter()
    oracle = network.distances()
    dist = np.ascontiguousarray(oracle.dist)
    t1 = time.perf_counter()
    space = build_states(
        network, oracle, rates, tau0_s=0.0, speed_mps=params.speed_mps, include_origin_state=config.include_origin_state
    )
    t2 = time.perf_counter()
    states_bytes = sum(getattr(space, f.name).nbytes for f in dataclasses.fields(space))

    def estimated(pairs: int, local_bytes: int) -> None:
        if announce is not None:
            # The lists, their blocks (a block's classes are a few per cent of its pairs) and the states.
            announce(int(pairs * (local_bytes + 0.2)) + states_bytes)

    matching = build_matching(space, rates, dist, params, config, directory, estimated)
    t3 = time.perf_counter()
    build_s = {"distances_s": t1 - t0, "states_s": t2 - t1, "matching_s": t3 - t2}
    np.savez(directory / "states.npz", **{f.name: getattr(space, f.name) for f in dataclasses.fields(space)})
    np.save(directory / "seeker_off.npy", matching.seeker_off)
    manifest = {
        "version": LISTS_FORMAT_VERSION,
        "n_od": len(rates),
        "n_pairs": matching.n_pairs,
        "local": matching.local.dtype.str,
        "stats": matching.stats,
        "build_s": build_s,
        "files": {name: [(directory / name).stat().st_size, _file_digest(directory / name)] for name in ENTRY_FILES},
    }
    manifest = json.loads(json.dumps(manifest, default=float))  # as it reads back, for its digest
    manifest["digest"] = _manifest_digest(manifest)
    (directory / "manifest.json").write_text(json.dumps(manifest, indent=1))
    _write_stamp(directory, manifest)
    _release_free_heap()
    return CachedLists(space=space, matching=matching, build_s=build_s, directory=directory)


def _release_free_heap() -> None:
    """Hand the build's freed temporaries back to the system (glibc keeps them in its per-thread arenas
    otherwise, and the sweeps that follow would add the mapped lists on top of them)."""
    with contextlib.suppress(OSError, AttributeError):  # not glibc: nothing to do
        ctypes.CDLL("libc.so.6").malloc_trim(0)


#: The entry's data files, each with its size and SHA-256 in the manifest.
ENTRY_FILES = ("states.npz", "seeker_off.npy", "blocks.npz", "local.bin")
STAMP = "verified.json"


class DamagedEntry(ValueError):
    """A cache entry whose content does not check out (the message says why)."""


def _open_entry(
    directory: Path, network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig
) -> CachedLists | None:
    """The cached structure in ``directory``, or None (absent, or damaged and then deleted)."""
    if not directory.is_dir():
        return None
    n_od = len(rates)
    try:
        manifest = json.loads((directory / "manifest.json").read_text())
        if (
            not isinstance(manifest, dict)
            or manifest.get("version") != LISTS_FORMAT_VERSION
            or manifest.get("n_od") != n_od
        ):
            raise DamagedEntry("it was written for other inputs")
        _verify_files(directory, manifest)
        with np.load(directory / "states.npz", allow_pickle=False) as data:
            space = StateSpace(**{f.name: data[f.name] for f in dataclasses.fields(StateSpace)})
        problem = space.problem(n_od, network.n_nodes, network.n_arcs)
        if problem is not None:
            raise DamagedEntry(f"its states are inconsistent ({problem})")
        seeker_off = np.load(directory / "seeker_off.npy", allow_pickle=False)
        if (
            seeker_off.dtype != np.int64
            or seeker_off.shape != (n_od + 1,)
            or seeker_off[0] != 0
            or int(seeker_off[-1]) != manifest.get("n_pairs")
            or np.any(np.diff(seeker_off) < 0)
        ):
            raise DamagedEntry("its offsets are not monotone from 0 to the manifest's pair count")
        geometry = ListGeometry.of(space, rates, params, config, lambda: network.distances().dist)
        matching = Matching.open(
            directory, seeker_off, manifest.get("stats", {}), manifest["local"], geometry, n_classes=space.n_classes
        )
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as exc:  # npz: a zip
        why = str(exc) if isinstance(exc, DamagedEntry) else f"{type(exc).__name__}: {one_line(exc)}"
        print(
            f"rpbench: note: the cached prediction structure {directory.name} is unusable ({why}); rebuilding it",
            file=sys.stderr,
        )
        shutil.rmtree(directory, ignore_errors=True)
        return None
    zero = {k: 0.0 for k in ("distances_s", "states_s", "matching_s")}
    return CachedLists(space=space, matching=matching, build_s=zero, directory=directory)


def _verify_files(directory: Path, manifest: dict) -> None:
    """Check the manifest's digest and each file's size; re-hash the files unless the stamp vouches for them."""
    if manifest.get("digest") != _manifest_digest(manifest):
        raise DamagedEntry("its manifest does not match its SHA-256 digest")
    files = manifest.get("files")
    if not isinstance(files, dict) or sorted(files) != sorted(ENTRY_FILES):
        raise DamagedEntry("its manifest does not list its files")
    for name, (size, _) in files.items():
        actual = (directory / name).stat().st_size
        if actual != size:
            raise DamagedEntry(f"its file {name} holds {actual} bytes, expected {size}")
    if _read_stamp(directory) == _stamp(directory, manifest):
        return
    for name, (_, digest) in files.items():
        if _file_digest(directory / name) != digest:
            raise DamagedEntry(f"its file {name} does not match its SHA-256 digest (changed on disk)")
    with contextlib.suppress(OSError):  # a read-only cache: verified again next time
        _write_stamp(directory, manifest)


def _file_digest(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def _manifest_digest(manifest: dict) -> str:
    body = {k: v for k, v in manifest.items() if k != "digest"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def _stamp(directory: Path, manifest: dict) -> dict:
    """What the stamp of a verified entry holds: the manifest's digest and each file's identity on disk
    (``ctime`` changes with any write, and cannot be set back the way ``mtime`` can)."""
    identity = {}
    for name in ENTRY_FILES:
        st = (directory / name).stat()
        identity[name] = [st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino]
    return {"manifest": manifest.get("digest"), "files": identity}


def _read_stamp(directory: Path) -> object:
    try:
        return json.loads((directory / STAMP).read_text())
    except (OSError, ValueError):
        return None


def _write_stamp(directory: Path, manifest: dict) -> None:
    """Record that the files' digests matched (atomically: a torn stamp only costs a re-hash)."""
    tmp = directory / f".{STAMP}.{os.getpid()}.tmp"
    try:
        tmp.write_text(json.dumps(_stamp(directory, manifest)))
        os.replace(tmp, directory / STAMP)
    finally:
        tmp.unlink(missing_ok=True)
