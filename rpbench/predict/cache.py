"""On-disk cache of solved predictions (in :func:`rpbench.files.paths.cache_dir`, never in the repository).

The key hashes everything the result depends on: the network's content hash
(which covers scipy's version, hence the shortest paths), the canonical OD
arrays and rates, the network-side parameters (R̄, D̄, v), every
:class:`~.config.PredictConfig` field and :data:`MODEL_VERSION` (bump it when
the model's arithmetic changes).  Only the per-OD and per-state results are
stored (a few MB for the full 39,510-OD table); the matching sets are not.
Entries are plain arrays: :mod:`.prediction` turns them back into a
:class:`~.prediction.Prediction`.  The manifest stored beside them names each
member's dtype, shape and SHA-256 (computed from the arrays before the entry
is renamed into place), and every load checks the members it reads against
it, so a value changed on disk is caught, not used.  A truncated, corrupt,
incomplete or changed entry, or one without digests (written by an older
rpbench), is deleted and recomputed (one note on stderr), never an error
that repeats on every run.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import sys
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import one_line
from rpbench.files.paths import cache_dir, cache_write_error, temporary_file
from rpbench.network import RoadNetwork
from rpbench.predict.config import PredictConfig
from rpbench.predict.rates import OdRates
from rpbench.scenarios.base import Params

MODEL_VERSION = "2"  # 2: Anderson mixing solves on an updated QR factorisation (last bits differ)
PARAM_FIELDS = ("max_pickup_m", "max_detour_m", "speed_mps")


def cache_key(network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig) -> str:
    h = hashlib.sha256()
    h.update(f"predict|{MODEL_VERSION}|{network.content_hash}|".encode())
    for arr in (rates.origin, rates.destination, rates.rate_per_s, rates.od_id):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(json.dumps({k: float(getattr(params, k)) for k in PARAM_FIELDS}, sort_keys=True).encode())
    h.update(json.dumps(config.as_dict(), sort_keys=True, default=str).encode())
    return h.hexdigest()[:24]


def cache_path(key: str) -> Path:
    return cache_dir() / f"predict-{key}.npz"


#: Everything reading a damaged ``.npz`` can raise: a truncated or corrupt zip (BadZipFile, EOFError,
#: zlib.error), a bad ``.npy`` header or pickled member (ValueError, UnpicklingError), a missing member
#: (KeyError), bad JSON or text (ValueError), an unreadable file (OSError).
READ_ERRORS = (
    OSError,
    EOFError,
    ValueError,
    KeyError,
    TypeError,
    zipfile.BadZipFile,
    zlib.error,
    pickle.UnpicklingError,
)


def save(key: str, arrays: dict[str, np.ndarray], info: dict) -> Path:
    """Write a prediction's arrays and facts atomically (a crash never leaves a half-written entry).

    A manifest of the members (name, dtype, shape, SHA-256) is stored beside
    them, so a load can tell a complete, unchanged entry from a damaged one.
    A cache that cannot be written is a :class:`~rpbench.exceptions.CacheError`.
    """
    payload: dict[str, Any] = {name: np.asarray(a) for name, a in arrays.items()}  # Any: numpy's savez stub
    payload["info_json"] = _json_bytes(info)
    manifest = {name: [a.dtype.str, list(a.shape), member_digest(a)] for name, a in payload.items()}
    payload["manifest_json"] = _json_bytes(manifest)
    path = cache_path(key)
    tmp = temporary_file(path)
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, **payload)
        os.replace(tmp, path)
    except BaseException as exc:  # disk full, permissions, Ctrl-C: no temporary file left behind
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise cache_write_error(path, exc) from None
        raise
    return path


def member_digest(a: np.ndarray) -> str:
    """SHA-256 of one stored member: its dtype, shape and bytes."""
    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}|{a.shape}|".encode())
    h.update(a.data.cast("B"))
    return h.hexdigest()


def load(key: str, n_ods: int, *, skip: frozenset[str] = frozenset()) -> tuple[dict[str, np.ndarray], dict] | None:
    """The cached (arrays, facts) of a prediction over ``n_ods`` ODs, or None when it must be computed.

    The arrays named in ``skip`` are neither read nor checked (an ``.npz`` is
    read member by member): a dispatcher needs the per-OD arrays only, a few
    MB instead of about 100 MB of per-state arrays for the month table.

    An entry that cannot be read, is incomplete or does not match its
    digests is deleted (with one note on stderr) so the caller recomputes and
    rewrites it, instead of failing on it, or using changed values, forever.
    """
    path = cache_path(key)
    try:
        before = path.stat()
    except OSError:
        return None  # not cached (yet)
    try:
        arrays, info_bytes, manifest = _read_entry(path, skip)
        problem = _entry_problem(arrays, info_bytes, manifest, skip, n_ods)
        info = json.loads(bytes(info_bytes).decode()) if problem is None else {}
        if problem is None and not isinstance(info, dict):
            problem = "is unreadable (its facts are not a JSON object)"
    except READ_ERRORS as exc:
        problem = f"is unreadable ({type(exc).__name__}: {one_line(exc)})"
    if problem is None:
        return arrays, info
    _discard(path, before, problem)
    return None


def _json_bytes(obj) -> np.ndarray:
    return np.frombuffer(json.dumps(obj, default=float).encode(), dtype=np.uint8)


def _read_entry(path: Path, skip: frozenset[str] = frozenset()) -> tuple[dict[str, np.ndarray], np.ndarray, Any]:
    """(arrays, the facts' JSON bytes, manifest) of an entry; the manifest is None when the entry has none."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files if not name.endswith("_json") and name not in skip}
        info = data["info_json"]
        manifest = json.loads(bytes(data["manifest_json"]).decode()) if "manifest_json" in data.files else None
    return arrays, info, manifest


def _entry_problem(
    arrays: dict[str, np.ndarray], info: np.ndarray, manifest: Any, skip: frozenset[str], n_ods: int
) -> str | None:
    """What makes a readable entry unusable (None when it is complete and matches its digests)."""
    if not isinstance(manifest, dict) or not all(isinstance(v, list) and len(v) == 3 for v in manifest.values()):
        return "has no content digests (written by an older rpbench)"
    if "info_json" not in manifest or set(arrays) - set(manifest):
        return "is incomplete (its manifest does not list every member)"
    members = {**arrays, "info_json": info}
    for name, (dtype, shape, digest) in manifest.items():
        if name in skip:
            continue
        a = members.get(name)
        if a is None or a.dtype.str != dtype or list(a.shape) != shape:
            return f"is incomplete (array {name!r} is missing or has the wrong type or shape)"
        if member_digest(a) != digest:
            return f"does not match its SHA-256 digest (array {name!r} changed on disk)"
    if len(arrays.get("od_p_seeker", ())) != n_ods:
        return f"does not hold {n_ods} ODs"
    return None


def _discard(path: Path, before: os.stat_result, problem: str) -> None:
    """Delete a bad entry, unless another process has replaced it meanwhile (then it is the new one)."""
    try:
        now = path.stat()
        if (now.st_ino, now.st_mtime_ns, now.st_size) == (before.st_ino, before.st_mtime_ns, before.st_size):
            path.unlink()
    except OSError:
        pass  # gone already, or not ours to delete: recomputing is enough
    print(f"rpbench: note: the cached prediction {path.name} {problem}; recomputing it", file=sys.stderr)
