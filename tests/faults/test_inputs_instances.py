"""Bad snapshot instance files (``rpbench bench FILE.npz``): one line and exit status 2, no --csv written,
and nothing allocated from sizes a file merely declares."""

from __future__ import annotations

import io
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest

import rpbench.model.instances as instances
from rpbench.model import AssignmentModel, PairingModel, TripPackingModel
from rpbench.model.instances import load_instance, save_instance

from .test_inputs_helpers import cli_error, cli_ok, flip_byte, truncate


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


MODELS = {
    # 3 passengers x 2 vehicles, each passenger with a keep-waiting column
    "assignment": AssignmentModel(3, 2, [0, 0, 1, 1, 2], [-1, 0, -1, 1, -1], [0, 5000, 0, 7000, 0], name="a"),
    "trip_packing": TripPackingModel(3, 2, [0, 1, 0], [0, 1, 0], [-1, -1, 2], [100, 200, 900], name="t"),
    "pairing": PairingModel(4, [0, 1, 2], [1, 2, 3], [10, 20, 30], name="p"),
}


def saved(tmp_path: Path, structure: str = "assignment") -> Path:
    return save_instance(tmp_path / f"{structure}.npz", MODELS[structure], {"status": "optimal"})


def members(path: Path) -> dict[str, np.ndarray]:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def rewrite(path: Path, change) -> Path:
    """The instance with its arrays passed through ``change(dict) -> dict`` (a valid npz again)."""
    arrays = change(members(path))
    np.savez_compressed(path, **arrays)
    return path


def npy_bytes(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def lying_header(path: Path) -> None:
    """``values.npy`` declares 2e9 float64 (16 GB) but holds 5."""
    entries = {f"{k}.npy": npy_bytes(v) for k, v in members(path).items()}
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (2_000_000_000,)})
    entries["values.npy"] = header.getvalue() + np.zeros(5).tobytes()
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in entries.items():
            zf.writestr(name, data)


def with_pickled_member(path: Path) -> None:
    entries = {f"{k}.npy": npy_bytes(v) for k, v in members(path).items()}
    buffer = io.BytesIO()
    np.save(buffer, np.array([{"x": 1}], dtype=object), allow_pickle=True)
    entries["meta_json.npy"] = buffer.getvalue()
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in entries.items():
            zf.writestr(name, data)


def npy_renamed(path: Path) -> None:
    np.save(path.with_suffix(".tmp.npy"), np.arange(10))
    path.with_suffix(".tmp.npy").replace(path)


def replace(name: str, value):
    return lambda path: rewrite(path, lambda m: {**m, name: value})


def drop(name: str):
    return lambda path: rewrite(path, lambda m: {k: v for k, v in m.items() if k != name})


BAD_FILES = {
    # case: (structure, damage, what the line says)
    "2e9 passengers declared": ("assignment", replace("n_passengers", np.array(2 * 10**9)), "must be an integer in"),
    "1e12 vehicles declared": ("assignment", replace("n_vehicles", np.array(10**12)), "must be an integer in"),
    "more passengers than columns": ("assignment", replace("n_passengers", np.array(5000)), "exceeds the 5 columns"),
    "negative order count": ("pairing", replace("n_orders", np.array(-1)), "n_orders = -1 must be an integer"),
    "fractional request count": ("trip_packing", replace("n_requests", np.array(3.0)), "n_requests = 3.0 must be"),
    "size given as an array": ("trip_packing", replace("n_vehicles", np.array([1, 2])), "an array of shape (2,)"),
    "array header declares 16 GB": ("assignment", lying_header, "declares shape (2000000000,)"),
    "truncated": ("assignment", lambda p: truncate(p, 0.7), "is corrupt or not an rpbench instance"),
    "a compressed byte flipped": ("pairing", lambda p: flip_byte(p, 60), "is corrupt or not an rpbench instance"),
    "empty file": ("assignment", lambda p: p.write_bytes(b""), "is corrupt or not an rpbench instance"),
    "text file": ("assignment", lambda p: p.write_text("instance,values\n"), "is corrupt or not an rpbench instance"),
    "an .npy renamed .npz": ("assignment", npy_renamed, "is corrupt or not an rpbench instance"),
    "a Python object inside": ("assignment", with_pickled_member, "holds Python objects"),
    "column array missing": ("assignment", drop("col_vehicle"), "missing array(s) col_vehicle"),
    "values missing": ("pairing", drop("values"), "missing array(s) values"),
    "index beyond int32": ("pairing", replace("col_b", np.array([1, 2, 2**32 + 3])), "holds an index outside"),
    "index beyond the declared count": ("pairing", replace("col_b", np.array([1, 2, 9])), "outside [0, 3]"),
    "float column indices": ("pairing", replace("col_a", np.array([0.0, 1.0, 2.0])), "must be an integer array"),
    "column arrays of another length": ("pairing", replace("col_a", np.array([0, 1])), "must be an integer array of 3"),
    "complex values": ("pairing", replace("values", np.array([1 + 1j, 2, 3])), "one-dimensional real array"),
    "two-dimensional values": ("pairing", replace("values", np.ones((3, 2))), "one-dimensional real array"),
    "NaN value": ("pairing", replace("values", np.array([1.0, np.nan, 3.0])), "must be finite"),
    "meta not an object": ("assignment", replace("meta_json", np.array("[1, 2]")), "meta_json is not a JSON object"),
    "meta not JSON": ("assignment", replace("meta_json", np.array("{status")), "is corrupt"),
    "another format": ("assignment", replace("format", np.array("rpbench-instance-0")), "is not an rpbench instance"),
    "unknown structure": ("assignment", replace("structure", np.array("tsp")), "is corrupt"),
    "unknown pairing objective": ("pairing", replace("objective", np.array("fastest")), "objective 'fastest' unknown"),
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_instance_file_is_one_line(capsys, tmp_path, case):
    structure, damage, message = BAD_FILES[case]
    path = saved(tmp_path, structure)
    damage(path)
    csv = tmp_path / "bench.csv"
    tracemalloc.start()
    try:
        line = cli_error(capsys, "bench", path, "--solver", "highs", "--repeat", "1", "--no-isolate", "--csv", csv)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert message in line and str(path) in line, line
    assert not csv.exists()
    assert peak < 200 * 2**20  # nothing allocated from what the file merely declares


def test_total_array_bytes_are_capped(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(instances, "MAX_ARRAY_BYTES", 1000)
    line = cli_error(capsys, "bench", saved(tmp_path), "--solver", "highs", "--no-isolate")
    assert "declares more than 1,000 bytes of arrays" in line


@pytest.mark.parametrize("structure", MODELS)
def test_valid_instances_still_round_trip(capsys, tmp_path, structure):
    model, meta = load_instance(saved(tmp_path, structure))
    original = MODELS[structure]
    assert meta == {"status": "optimal"} and model.structure == original.structure
    np.testing.assert_array_equal(model.values, original.values)
    np.testing.assert_array_equal(model.column_rows()[1], original.column_rows()[1])
    cli_ok(capsys, "bench", tmp_path / f"{structure}.npz", "--solver", "highs", "--repeat", "1", "--no-isolate")


def test_shipped_example_instances_still_load():
    folder = Path(__file__).resolve().parents[2] / "instances" / "examples"
    files = sorted(folder.glob("*.npz"))
    assert files
    for path in files:
        load_instance(path)
