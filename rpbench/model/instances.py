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
import math
import pickle
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import ModelError, ResultsError, one_line
from rpbench.files import check_schema, parse_json
from rpbench.model import AssignmentModel, Model, PairingModel, Status, Structure, TripPackingModel

INSTANCE_FORMAT = "rpbench-instance-1"
#: Largest declared row count (passengers, vehicles, requests, orders): ~1000 times the largest fleet or
#: order count of a Haikou run, and small enough that per-row arrays stay within a few hundred MB.
MAX_ROWS = 10_000_000
#: Largest total of (uncompressed) array bytes in one instance file.
MAX_ARRAY_BYTES = 4 << 30
#: What reading a truncated, corrupt or foreign file raises (zip, zlib, .npy header, pickle, short data).
_READ_ERRORS = (
    OSError,
    EOFError,
    ValueError,
    KeyError,
    TypeError,
    zipfile.BadZipFile,
    zlib.error,
    pickle.UnpicklingError,
    NotImplementedError,
)
_HEADER_READERS = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
#: The provenance fields of ``meta_json`` (rpbench snapshot writes them all; a hand-made instance may have
#: none) and the types their values must have: ``objective`` is what the run's solver reached (null if none).
META_TYPES: dict[str, type | tuple[type, ...]] = {
    "scenario": str,
    "scenario_name": str,
    "seed": int,
    "strategy": str,
    "round": int,
    "t_s": float,
    "preset": str,
    "objective": (float, type(None)),
    "status": str,
    "size": dict,
}
STATUSES = frozenset(s.value for s in Status)
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
    arrays: dict[str, Any] = {
        "format": np.array(INSTANCE_FORMAT),
        "structure": np.array(model.structure.value),
        "values": model.values,
        "unit_m": np.array(model.unit_m),
        "name": np.array(model.name),
        "meta_json": np.array(json.dumps(meta or {})),
    }
    for f in _FIELDS[model.structure]:
        arrays[f] = np.asarray(getattr(model, f))
    if model.structure == Structure.PAIRING:
        arrays["objective"] = np.array(model.objective)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_npz(path, arrays)
    return path


#: The timestamp of every member of an instance file: np.savez stamps the time of writing, which would make
#: two builds of the same instance differ in their bytes (and their SHA-256).
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


def write_npz(path: Path, arrays: dict[str, Any]) -> None:
    """``np.savez_compressed``'s format (one deflated ``NAME.npy`` member per array, read by ``np.load``),
    written with fixed member times and order: the same arrays give the same bytes."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            with zf.open(info, "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)


def load_instance(path: str | Path) -> tuple[Model, dict[str, Any]]:
    """Read an instance file; return ``(model, meta)``.  Raises ResultsError on a corrupt file.

    Nothing is allocated from what the file merely declares: every array's
    header must match the bytes its zip member holds (within
    :data:`MAX_ARRAY_BYTES` in all), and the declared row counts must be
    scalars in ``[0, MAX_ROWS]`` that the column arrays can back, before the
    model is built (a crafted file declaring 2e9 passengers once made
    ``rpbench bench`` allocate 15 GiB).
    """
    path = Path(path)
    if not path.is_file():
        raise ResultsError(f"snapshot file {str(path)!r} does not exist")
    data = _read_arrays(path)
    if str(data.get("format", "")) != INSTANCE_FORMAT:
        raise ResultsError(
            f"snapshot file {str(path)!r} is not an rpbench instance (format "
            f"{str(data.get('format', 'missing'))!r}, expected {INSTANCE_FORMAT!r})"
        )
    try:
        structure = Structure(str(data["structure"]))
        missing = [f for f in ("values", "unit_m", "name", *_FIELDS[structure]) if f not in data]
        if missing:
            raise KeyError(", ".join(missing))
        _check_declared_sizes(data, structure)
        unit_m, name = float(data["unit_m"]), str(data["name"])
        model: Model
        if structure == Structure.ASSIGNMENT:
            model = AssignmentModel(
                int(data["n_passengers"]),
                int(data["n_vehicles"]),
                data["col_passenger"],
                data["col_vehicle"],
                data["values"],
                unit_m=unit_m,
                name=name,
            )
        elif structure == Structure.TRIP_PACKING:
            model = TripPackingModel(
                int(data["n_requests"]),
                int(data["n_vehicles"]),
                data["col_vehicle"],
                data["col_request1"],
                data["col_request2"],
                data["values"],
                unit_m=unit_m,
                name=name,
            )
        else:
            model = PairingModel(
                int(data["n_orders"]),
                data["col_a"],
                data["col_b"],
                data["values"],
                objective=str(data.get("objective", "weight")),
                unit_m=unit_m,
                name=name,
            )
        meta = parse_json(str(data.get("meta_json", "{}")), "meta_json", ResultsError)
    except ResultsError as exc:  # malformed or too deeply nested
        raise ResultsError(f"snapshot file {str(path)!r} is corrupt: {exc}") from None
    except (KeyError, ValueError, TypeError, OverflowError, ModelError) as exc:
        what = f"missing array(s) {exc.args[0]}" if isinstance(exc, KeyError) else one_line(exc)
        raise ResultsError(f"snapshot file {str(path)!r} is corrupt: {what}") from None
    _check_meta(meta, path)
    return model, meta


def _check_meta(meta: Any, path: Path) -> None:
    """The metadata fields rpbench reads (:data:`META_TYPES`) hold values of their types; each is optional."""
    where = f"snapshot file {str(path)!r}"
    if not isinstance(meta, dict):
        raise ResultsError(f"{where} is corrupt: meta_json is not a JSON object (it holds a {type(meta).__name__})")
    for key, want in META_TYPES.items():
        if key in meta:
            check_schema(meta, {key: want}, f"{where}, metadata", ResultsError)
    objective = meta.get("objective")
    if objective is not None and not math.isfinite(objective):
        raise ResultsError(f"{where}, metadata: objective = {objective!r} is not a finite number")
    if "status" in meta and meta["status"] not in STATUSES:
        raise ResultsError(
            f"{where}, metadata: status = {meta['status']!r} is not one of {', '.join(sorted(STATUSES))}"
        )


def _read_arrays(path: Path) -> dict[str, np.ndarray]:
    """Every array of the file, after checking their declared sizes against the file (see load_instance)."""
    try:
        _check_members(path)
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except ResultsError:
        raise
    except _READ_ERRORS as exc:
        raise ResultsError(
            f"snapshot file {str(path)!r} is corrupt or not an rpbench instance: {one_line(exc)}"
        ) from None


def _check_members(path: Path) -> None:
    """Each ``.npy`` member's header (shape x item size) must match the bytes the member holds.

    np.load allocates the array its header declares before reading the data,
    so a lying header is refused here, from the zip directory and the headers
    alone; the total is capped so a decompression bomb is never inflated.
    """
    total = 0
    with zipfile.ZipFile(path) as zf:
        for info in zf.infolist():
            total += info.file_size
            if total > MAX_ARRAY_BYTES:
                raise ResultsError(
                    f"snapshot file {str(path)!r} declares more than {MAX_ARRAY_BYTES:,} bytes "
                    "of arrays; not an instance rpbench wrote"
                )
            with zf.open(info) as fh:
                version = np.lib.format.read_magic(fh)
                if version not in _HEADER_READERS:
                    raise ValueError(f"array {info.filename!r} has unsupported .npy version {version}")
                shape, _, dtype = _HEADER_READERS[version](fh)
                if dtype.hasobject:
                    raise ValueError(f"array {info.filename!r} holds Python objects")
                declared = fh.tell() + math.prod(shape) * dtype.itemsize
            if declared != info.file_size:
                raise ValueError(
                    f"array {info.filename!r} declares shape {shape} of {dtype} "
                    f"({declared:,} bytes) but holds {info.file_size:,} bytes"
                )


def _check_declared_sizes(data: dict[str, np.ndarray], structure: Structure) -> None:
    """Row counts and column arrays checked before the model (which allocates per declared row) is built."""
    values = data["values"]
    if values.ndim != 1 or values.dtype.kind not in "fiu":
        raise ValueError(f"values must be a one-dimensional real array, not {values.dtype}{values.shape}")
    n_cols = len(values)
    for name in _FIELDS[structure]:
        if name.startswith("n_"):
            _check_count(name, data[name])
        else:
            _check_column(name, data[name], n_cols)
    # Every passenger needs at least its keep-waiting column: more passengers than columns is a lie.
    if structure == Structure.ASSIGNMENT and int(data["n_passengers"]) > n_cols:
        raise ValueError(
            f"n_passengers = {int(data['n_passengers'])} exceeds the {n_cols} columns; "
            "every passenger has at least one column"
        )


def _check_count(name: str, arr: np.ndarray) -> None:
    if arr.ndim != 0 or arr.dtype.kind not in "iu" or not 0 <= int(arr) <= MAX_ROWS:
        shown = repr(arr.item()) if arr.ndim == 0 else f"an array of shape {arr.shape}"
        raise ValueError(f"{name} = {shown} must be an integer in [0, {MAX_ROWS:,}]")


def _check_column(name: str, arr: np.ndarray, n_cols: int) -> None:
    # The model stores indices as int32: an int64 index of 2**32 would wrap around to 0 unnoticed.
    if arr.ndim != 1 or arr.dtype.kind not in "iu" or len(arr) != n_cols:
        raise ValueError(f"{name} must be an integer array of {n_cols} entries, not {arr.dtype}{arr.shape}")
    if len(arr) and (int(arr.min()) < -1 or int(arr.max()) >= MAX_ROWS):
        raise ValueError(f"{name} holds an index outside [-1, {MAX_ROWS:,})")


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


def load_instances(paths: list[str | Path]) -> tuple[list[Model], dict[str, float]]:
    """Models of every instance file under ``paths``, named uniquely, and the optima their runs proved.

    Models are renamed after their file (``toy_mb_round00025``; the parent
    folder is prefixed when two files share a name) so a benchmark table
    tells them apart.  The second value maps a model name to the objective
    recorded in its metadata when the run's solver proved it optimal.
    """
    files = list(dict.fromkeys(find_instances(paths)))  # a file named twice is solved once
    stems = [f.stem for f in files]
    models, recorded, used = [], {}, set()
    for f, stem in zip(files, stems, strict=True):
        label = stem if stems.count(stem) == 1 else f"{f.parent.name}/{stem}"
        label = label if label not in used else str(f)
        used.add(label)
        model, meta = load_instance(f)
        model = model.renamed(label)
        models.append(model)
        if meta.get("status") == "optimal" and meta.get("objective") is not None:
            recorded[label] = float(meta["objective"])
    return models, recorded
