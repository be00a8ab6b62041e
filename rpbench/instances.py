"""Snapshot instance files: a solver-agnostic model frozen to disk, and read back exactly.

One instance = one ``.npz`` file (numpy's zip of arrays, read with
``allow_pickle=False``) holding:

* ``format``: ``"rpbench-instance-1"``;
* ``structure``: ``"assignment"``, ``"trip_packing"`` or ``"pairing"``;
* ``values`` (float64, integral in units of ``unit_m`` metres), ``unit_m``, ``name``;
* the structure's index arrays — assignment: ``n_passengers``, ``n_vehicles``,
  ``col_passenger``, ``col_vehicle`` (-1 = keep waiting); trip packing:
  ``n_requests``, ``n_vehicles``, ``col_vehicle``, ``col_request1``,
  ``col_request2`` (-1 = one-request trip); pairing: ``n_orders``, ``col_a``,
  ``col_b``, ``objective`` (``weight`` | ``cardinality_then_weight``);
* ``meta_json``: provenance as a JSON string (scenario, strategy, round,
  time, the objective the run's solver reached).

Loading rebuilds the model through its validating constructor, so a
damaged file fails with one clear error instead of a wrong model.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import ModelError, ResultsError
from rpbench.model import AssignmentModel, PairingModel, Structure, TripPackingModel

FORMAT = "rpbench-instance-1"
_FIELDS = {
    Structure.ASSIGNMENT: ("n_passengers", "n_vehicles", "col_passenger", "col_vehicle"),
    Structure.TRIP_PACKING: ("n_requests", "n_vehicles", "col_vehicle", "col_request1", "col_request2"),
    Structure.PAIRING: ("n_orders", "col_a", "col_b"),
}


def save_instance(path: str | Path, model, meta: dict[str, Any] | None = None) -> Path:
    """Write ``model`` (and provenance ``meta``) to ``path`` (``.npz`` appended if missing)."""
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz") if path.suffix else path.with_suffix(".npz")
    arrays: dict[str, Any] = {"format": np.array(FORMAT), "structure": np.array(model.structure.value),
                              "values": model.values, "unit_m": np.array(model.unit_m),
                              "name": np.array(model.name), "meta_json": np.array(json.dumps(meta or {}))}
    for f in _FIELDS[model.structure]:
        arrays[f] = np.asarray(getattr(model, f))
    if model.structure == Structure.PAIRING:
        arrays["objective"] = np.array(model.objective)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)
    return path


def load_instance(path: str | Path):
    """Read an instance file; return ``(model, meta)``.  Raises ResultsError on a corrupt file."""
    path = Path(path)
    if not path.is_file():
        raise ResultsError(f"snapshot file {str(path)!r} does not exist")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise ResultsError(f"snapshot file {str(path)!r} is corrupt or not an rpbench instance: {exc}") from None
    if str(data.get("format", "")) != FORMAT:
        raise ResultsError(f"snapshot file {str(path)!r} is not an rpbench instance (format "
                           f"{str(data.get('format', 'missing'))!r}, expected {FORMAT!r})")
    try:
        structure = Structure(str(data["structure"]))
        missing = [f for f in ("values", "unit_m", "name", *_FIELDS[structure]) if f not in data]
        if missing:
            raise KeyError(", ".join(missing))
        common = dict(unit_m=float(data["unit_m"]), name=str(data["name"]))
        if structure == Structure.ASSIGNMENT:
            model = AssignmentModel(int(data["n_passengers"]), int(data["n_vehicles"]), data["col_passenger"],
                                    data["col_vehicle"], data["values"], **common)
        elif structure == Structure.TRIP_PACKING:
            model = TripPackingModel(int(data["n_requests"]), int(data["n_vehicles"]), data["col_vehicle"],
                                     data["col_request1"], data["col_request2"], data["values"], **common)
        else:
            model = PairingModel(int(data["n_orders"]), data["col_a"], data["col_b"], data["values"],
                                 objective=str(data.get("objective", "weight")), **common)
        meta = json.loads(str(data.get("meta_json", "{}")))
    except (KeyError, ValueError, TypeError, ModelError, json.JSONDecodeError) as exc:
        raise ResultsError(f"snapshot file {str(path)!r} is corrupt: {exc}") from None
    return model, meta


def find_instances(paths: list[str | Path]) -> list[Path]:
    """Instance files named directly or found (recursively) in folders."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out += sorted(p.rglob("*.npz"))
        elif p.is_file():
            out.append(p)
        else:
            raise ResultsError(f"snapshot path {str(p)!r} does not exist")
    if not out:
        raise ResultsError(f"no snapshot instance files (*.npz) in {', '.join(map(str, paths))}")
    return out


def load_instances(paths: list[str | Path]) -> tuple[list, dict[str, float]]:
    """Models of every instance file under ``paths``, named uniquely, and the optima their runs proved.

    Models are renamed after their file (``toy_mb_round00025``; the parent
    folder is prefixed when two files share a name) so a benchmark table
    tells them apart.  The second value maps a model name to the objective
    recorded in its metadata when the run's solver proved it optimal.
    """
    files = list(dict.fromkeys(find_instances(paths)))          # a file named twice is solved once
    stems = [f.stem for f in files]
    models, recorded, used = [], {}, set()
    for f, stem in zip(files, stems):
        label = stem if stems.count(stem) == 1 else f"{f.parent.name}/{stem}"
        label = label if label not in used else str(f)
        used.add(label)
        model, meta = load_instance(f)
        model = model.renamed(label)
        models.append(model)
        if meta.get("status") == "optimal" and meta.get("objective") is not None:
            recorded[label] = float(meta["objective"])
    return models, recorded
