"""On-disk cache of solved predictions (in :func:`rpbench.paths.cache_dir`, never in the repository).

The key hashes everything the result depends on: the network's content hash
(which covers scipy's version, hence the shortest paths), the canonical OD
arrays and rates, the network-side parameters (R̄, D̄, v), every
:class:`~.config.PredictConfig` field and :data:`MODEL_VERSION` (bump it when
the model's arithmetic changes).  Only the per-OD and per-state results are
stored (a few MB for the full 39,510-OD table); the matching sets are not.
Entries are plain arrays: :mod:`.prediction` turns them back into a
:class:`~.prediction.Prediction`.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from rpbench.network import RoadNetwork
from rpbench.paths import cache_dir
from rpbench.predict.config import PredictConfig
from rpbench.predict.rates import OdRates
from rpbench.scenarios.base import Params

MODEL_VERSION = "1"
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


def save(key: str, arrays: dict[str, np.ndarray], info: dict) -> Path:
    """Write a prediction's arrays and facts atomically (a crash never leaves a half-written entry)."""
    payload = dict(arrays)
    payload["info_json"] = np.frombuffer(json.dumps(info, default=float).encode(), dtype=np.uint8)
    path = cache_path(key)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.savez(fh, **payload)
    os.replace(tmp, path)
    return path


def load(key: str, n_ods: int) -> tuple[dict[str, np.ndarray], dict] | None:
    """The cached (arrays, facts) of a prediction over ``n_ods`` ODs, or None (missing or unreadable entries
    are recomputed)."""
    path = cache_path(key)
    if not path.is_file():
        return None
    try:
        with np.load(path) as data:
            arrays = {name: data[name] for name in data.files if name != "info_json"}
            info = json.loads(bytes(data["info_json"]).decode())
    except (OSError, ValueError, KeyError, json.JSONDecodeError):
        return None
    if len(arrays.get("od_p_seeker", ())) != n_ods:
        return None
    return arrays, info
