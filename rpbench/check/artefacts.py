"""``artefacts``: the files a run's decisions depend on, copied into its folder, are the ones it used.

A run of ``vf`` names its value model in meta.json (``artefacts: {"value-model": DIGEST}``) and carries
a copy in ``runs/NAME/value-model/``.  The checker recomputes, with its own hashing: the SHA-256 of the
copy's model.json is the recorded digest, every array file's SHA-256 is the one model.json gives, the
arrays have the shapes it gives and the model covers the folder's network; and the scenario is not one
the model was trained on (a test day must be held out).  It does not re-run the dispatcher.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from rpbench.check.core import RunCheck
from rpbench.check.exact import EXACT_PLAN
from rpbench.check.folder import Folder
from rpbench.files.digests import file_sha256
from rpbench.strategies.value import VALUE_MODEL

#: Strategies whose runs must name a value model.
NEEDS_VALUE_MODEL = ("vf",)
_ARRAYS = ("values", "visits", "node_cell")


def check_artefacts(rc: RunCheck, f: Folder, name: str, run_dir: Path) -> None:
    record = f.meta["runs"][name]
    named = record.get("artefacts") or {}
    if not isinstance(named, dict):
        rc.fail("artefacts", "meta.json's artefacts is not a name -> digest table")
        return
    if record.get("source") in NEEDS_VALUE_MODEL and VALUE_MODEL not in named:
        rc.fail("artefacts", f"a {record.get('source')} run names no {VALUE_MODEL} in meta.json")
    for artefact, digest in named.items():
        if artefact == EXACT_PLAN:
            continue  # verified with the run's pairs and saving (:mod:`.exact`, ``exact-optimum``)
        if artefact != VALUE_MODEL:
            rc.fail("artefacts", f"unknown artefact {artefact!r}: the checker cannot verify it")
            continue
        problem = _value_model_problem(run_dir / artefact, str(digest), f)
        if problem is not None:
            rc.fail("artefacts", f"{name}/{artefact} ({str(digest)[:12]}): {problem}")
    if named:
        rc.checked["artefacts"] = len(named)


def _value_model_problem(folder: Path, digest: str, f: Folder) -> str | None:
    """What is wrong with the value model copy in ``folder`` (None: it is the recorded one, intact)."""
    description = folder / "model.json"
    if not description.is_file():
        return f"missing: the run folder holds no {folder.name}/model.json"
    if file_sha256(description) != digest:
        return "model.json is not the model the run recorded (its SHA-256 differs)"
    try:
        meta = json.loads(description.read_text(encoding="utf-8"))
        shape = (int(meta["n_cells"]), int(meta["n_bins"]))
        sums = meta["arrays"]
        arrays = {}
        for array in _ARRAYS:
            path = folder / f"{array}.npy"
            if not path.is_file():
                return f"{array}.npy is missing"
            if hashlib.sha256(path.read_bytes()).hexdigest() != sums[array]:
                return f"{array}.npy does not match its SHA-256 in model.json (edited or damaged)"
            arrays[array] = np.load(path, allow_pickle=False)
            if arrays[array].dtype.kind not in "iuf":
                return f"{array}.npy holds {arrays[array].dtype} values, not numbers"
        training = meta.get("training") or {}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        return f"unreadable ({type(exc).__name__}: {exc})"
    if arrays["values"].shape != shape or arrays["visits"].shape != shape:
        return f"its arrays are not of the shape {shape} model.json gives"
    if not np.isfinite(arrays["values"]).all():
        return "values.npy holds values that are not finite"
    node_cell = arrays["node_cell"]
    if node_cell.shape != (f.network.n_nodes,) or node_cell.min() < 0 or node_cell.max() >= shape[0]:
        return (
            f"node_cell.npy does not give a cell (0..{shape[0] - 1}) to each of the network's {f.network.n_nodes} nodes"
        )
    return _trained_on(f.meta.get("scenario") or {}, training)


def _trained_on(scenario: dict, training: dict) -> str | None:
    """Why the folder's scenario is one the model was trained on: the same generator and, for a dated
    scenario, one of its days, else one of its (seed, sample) draws."""
    if training.get("scenario") != scenario.get("name"):
        return None
    provenance = scenario.get("provenance") or {}
    runs = training.get("runs") or []
    date = provenance.get("date")
    if date is not None:
        return (
            f"the model was trained on {date}, the day this folder tests it on"
            if date in {r.get("date") for r in runs}
            else None
        )
    draw = (scenario.get("seed"), provenance.get("sample"))
    if draw in {(r.get("seed"), r.get("sample")) for r in runs}:
        return f"the model was trained on seed {draw[0]} at sample {draw[1]}, the draw this folder tests it on"
    return None
