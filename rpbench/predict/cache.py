"""On-disk cache of solved predictions (in :func:`rpbench.paths.cache_dir`, never in the repository).

The key hashes everything the result depends on: the network's content hash
(which covers scipy's version, hence the shortest paths), the canonical OD
arrays and rates, the network-side parameters (R̄, D̄, v), every
:class:`~.config.PredictConfig` field and :data:`MODEL_VERSION` (bump it when
the model's arithmetic changes).  Only the per-OD and per-state results are
stored (a few MB for the full 39,510-OD table); the matching sets are not.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..network import RoadNetwork
from ..paths import cache_dir
from ..scenario import Params
from .config import PredictConfig
from .rates import OdRates

MODEL_VERSION = "1"
PARAM_FIELDS = ("max_pickup_m", "max_detour_m", "speed_mps")
_STATE_FIELDS = ("state_od", "state_k", "state_head", "state_tau_s", "rho", "p_taker", "eta", "lam_taker")


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


def save(key: str, prediction) -> Path:
    """Write atomically (a crash never leaves a half-written entry)."""
    from .savings import Outcome  # local: avoid an import cycle at module load
    arrays = {f"od_{f.name}": getattr(prediction.od, f.name) for f in dataclasses.fields(Outcome)}
    arrays.update({name: getattr(prediction, name) for name in _STATE_FIELDS})
    arrays["info_json"] = np.frombuffer(json.dumps(prediction.info, default=float).encode(), dtype=np.uint8)
    path = cache_path(key)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)
    os.replace(tmp, path)
    return path


def load(key: str, network: RoadNetwork, rates: OdRates, config: PredictConfig):
    """The cached prediction, or None (missing or unreadable entries are recomputed)."""
    from .prediction import Prediction
    from .savings import Outcome
    path = cache_path(key)
    if not path.is_file():
        return None
    try:
        with np.load(path) as data:
            od = Outcome(**{f.name: data[f"od_{f.name}"] for f in dataclasses.fields(Outcome)})
            states = {name: data[name] for name in _STATE_FIELDS}
            info = json.loads(bytes(data["info_json"]).decode())
    except (OSError, ValueError, KeyError, json.JSONDecodeError):
        return None
    if len(od.p_seeker) != len(rates):
        return None
    return Prediction(node_id=network.node_id, rates=rates, params=info.get("params", {}), config=config, od=od,
                      info=info, from_cache=True, **states)
