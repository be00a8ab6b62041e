"""The value model artefact: three arrays and a JSON description that names their SHA-256.

A model folder holds ``values.npy`` (V, shape ``(n_cells, n_bins)``, metres of saving), ``visits.npy``
(transitions that left each state in training), ``node_cell.npy`` (each network node's cell) and
``model.json`` (the grid, the discount, the network's content hash, how it was trained, and each
array file's SHA-256).  The model's digest is the SHA-256 of ``model.json``'s bytes, so it covers the
arrays too; the same training gives the same bytes (``np.save`` and sorted-key JSON hold no clock).
Loading checks every array against its recorded digest and shape: an edited file is one error line.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import ParameterError, one_line
from rpbench.files import load_json_object
from rpbench.network import RoadNetwork
from rpbench.version import __version__

MODEL_JSON = "model.json"
ARRAYS = ("values", "visits", "node_cell")
MODEL_FORMAT = "rpbench-value-model"
MODEL_FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class ValueModel:
    """V(cell, time bin) and what it was learned from (:mod:`rpbench.valuefn.training`)."""

    values: np.ndarray  # (n_cells, n_bins) float64
    visits: np.ndarray  # (n_cells, n_bins) int64
    node_cell: np.ndarray  # (n_nodes,) int64
    cell_m: float
    bin_s: float
    discount: float
    network: str  # RoadNetwork.content_hash of the network it was learned on
    training: dict[str, Any] = field(default_factory=dict)

    @property
    def n_bins(self) -> int:
        return int(self.values.shape[1])

    def value_at(self, node: np.ndarray, t_s: np.ndarray | float) -> np.ndarray:
        """V of a vehicle at ``node`` at time ``t_s`` (times past the last bin read the last bin)."""
        b = np.clip(np.floor(np.asarray(t_s, dtype=np.float64) / self.bin_s), 0, self.n_bins - 1).astype(np.int64)
        return self.values[self.node_cell[np.asarray(node, dtype=np.int64)], b]

    def description(self, digests: dict[str, str]) -> dict[str, Any]:
        return {
            "format": MODEL_FORMAT,
            "format_version": MODEL_FORMAT_VERSION,
            "rpbench": __version__,
            "cell_m": self.cell_m,
            "bin_s": self.bin_s,
            "n_cells": int(self.values.shape[0]),
            "n_bins": self.n_bins,
            "discount": self.discount,
            "network": self.network,
            "n_nodes": len(self.node_cell),
            "training": self.training,
            "visited_states": int((self.visits > 0).sum()),
            "transitions": int(self.visits.sum()),
            "arrays": digests,
        }

    def check_network(self, network: RoadNetwork, where: str) -> None:
        if network.content_hash != self.network:
            raise ParameterError(
                f"{where}: the value model was learned on another road network ({self.network}, this "
                f"scenario's is {network.content_hash})"
            )


def save_model(model: ValueModel, folder: Path) -> str:
    """Write the model into the new folder ``folder`` (created here) and return its digest."""
    folder.mkdir()
    digests = {}
    for name in ARRAYS:
        path = folder / f"{name}.npy"
        np.save(path, np.ascontiguousarray(getattr(model, name)), allow_pickle=False)
        digests[name] = _sha256(path.read_bytes())
    text = json.dumps(model.description(digests), indent=1, sort_keys=True) + "\n"
    (folder / MODEL_JSON).write_text(text, encoding="utf-8")
    return _sha256(text.encode("utf-8"))


def save_model_atomically(model: ValueModel, final: Path) -> str:
    """:func:`save_model` into a staging folder beside ``final``, then renamed to it; a folder another
    process finished first is kept (same training, same bytes) and ours discarded."""
    final.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{final.name}.partial-{os.getpid()}-", dir=final.parent))
    try:
        digest = save_model(model, staging / "model")
        try:
            os.rename(staging / "model", final)
        except OSError:
            if not (final / MODEL_JSON).is_file():
                raise
        return digest
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def model_digest(folder: str | os.PathLike) -> str:
    """The digest of the model in ``folder`` (the SHA-256 of its model.json), without loading its arrays."""
    path = Path(folder) / MODEL_JSON
    try:
        return _sha256(path.read_bytes())
    except OSError as exc:
        raise ParameterError(f"value model {str(folder)!r}: cannot read {MODEL_JSON} ({exc.strerror or exc})") from None


def load_model(folder: str | os.PathLike) -> tuple[ValueModel, str]:
    """The model in ``folder`` and its digest, every array checked against model.json; one
    :class:`ParameterError` line naming the folder and the file otherwise."""
    folder = Path(folder)
    where = f"value model {str(folder)!r}"
    if not folder.is_dir():
        raise ParameterError(f"{where} is not a folder (train one with `rpbench train vf --out FOLDER`)")
    meta = load_json_object(folder / MODEL_JSON, f"{where}: {MODEL_JSON}", ParameterError)
    if meta.get("format") != MODEL_FORMAT or meta.get("format_version") != MODEL_FORMAT_VERSION:
        raise ParameterError(
            f"{where}: {MODEL_JSON} is not a {MODEL_FORMAT} version {MODEL_FORMAT_VERSION} description"
        )
    digests = meta.get("arrays")
    if not isinstance(digests, dict):
        raise ParameterError(f"{where}: {MODEL_JSON} names no array digests")
    arrays = {}
    for name in ARRAYS:
        path = folder / f"{name}.npy"
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise ParameterError(f"{where}: cannot read {name}.npy ({exc.strerror or exc})") from None
        if _sha256(data) != digests.get(name):
            raise ParameterError(f"{where}: {name}.npy does not match its digest in {MODEL_JSON} (edited or damaged)")
        try:  # the bytes just verified, not the file read again
            arrays[name] = np.load(io.BytesIO(data), allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise ParameterError(f"{where}: {name}.npy is not a .npy array ({one_line(exc)})") from None
        if arrays[name].dtype.kind not in ("iuf" if name == "values" else "iu"):
            kind = "numbers" if name == "values" else "integers"
            raise ParameterError(f"{where}: {name}.npy holds {arrays[name].dtype} values, not {kind}")
    try:
        shape = (int(meta["n_cells"]), int(meta["n_bins"]))
        model = ValueModel(
            values=arrays["values"].astype(np.float64, copy=False),
            visits=arrays["visits"].astype(np.int64, copy=False),
            node_cell=arrays["node_cell"].astype(np.int64, copy=False),
            cell_m=float(meta["cell_m"]),
            bin_s=float(meta["bin_s"]),
            discount=float(meta["discount"]),
            network=str(meta["network"]),
            training=dict(meta.get("training") or {}),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise ParameterError(f"{where}: {MODEL_JSON} is incomplete ({type(exc).__name__}: {exc})") from None
    if model.values.shape != shape or model.visits.shape != shape or model.node_cell.ndim != 1:
        raise ParameterError(f"{where}: its arrays do not have the shapes {MODEL_JSON} gives")
    if len(model.node_cell) and (model.node_cell.min() < 0 or model.node_cell.max() >= shape[0]):
        raise ParameterError(f"{where}: node_cell.npy names cells outside 0..{shape[0] - 1}")
    if not np.isfinite(model.values).all():
        raise ParameterError(f"{where}: values.npy holds values that are not finite")
    return model, _sha256((folder / MODEL_JSON).read_bytes())


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()
