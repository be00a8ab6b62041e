"""The value model artefact: written and read back bit for bit, its digest the SHA-256 of model.json, and
every edit, loss or malformed description refused in one ParameterError line naming the folder."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from rpbench.exceptions import ParameterError
from rpbench.scenarios.registry import build_scenario
from rpbench.valuefn.model import MODEL_JSON, ValueModel, load_model, model_digest, save_model, save_model_atomically


def hand_model(**changes) -> ValueModel:
    """Three cells, two bins of 600 s; four nodes (node 3 shares cell 2)."""
    fields = dict(
        values=np.array([[10.0, 11.0], [20.0, 21.0], [30.0, 31.0]]),
        visits=np.array([[1, 0], [2, 3], [0, 4]], dtype=np.int64),
        node_cell=np.array([0, 1, 2, 2], dtype=np.int64),
        cell_m=1000.0,
        bin_s=600.0,
        discount=0.9,
        network="net-hash",
        training={"scenario": "toy", "runs": [{"date": None, "seed": 7, "sample": 0.5, "orders": 3}]},
    )
    fields.update(changes)
    return ValueModel(**fields)


@pytest.fixture
def saved(tmp_path) -> Path:
    folder = tmp_path / "model"
    save_model(hand_model(), folder)
    return folder


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_saved_model_reads_back_the_same(saved):
    model, digest = load_model(saved)
    original = hand_model()
    for name in ("values", "visits", "node_cell"):
        assert np.array_equal(getattr(model, name), getattr(original, name))
        assert getattr(model, name).dtype == getattr(original, name).dtype
    assert (model.cell_m, model.bin_s, model.discount, model.network) == (1000.0, 600.0, 0.9, "net-hash")
    assert model.training == original.training
    assert sorted(p.name for p in saved.iterdir()) == ["model.json", "node_cell.npy", "values.npy", "visits.npy"]


def test_the_digest_is_the_sha256_of_model_json_which_names_each_arrays_sha256(tmp_path):
    folder = tmp_path / "m"
    digest = save_model(hand_model(), folder)
    assert digest == sha256(folder / MODEL_JSON) == model_digest(folder) == load_model(folder)[1]
    meta = json.loads((folder / MODEL_JSON).read_text())
    assert meta["arrays"] == {name: sha256(folder / f"{name}.npy") for name in ("values", "visits", "node_cell")}
    assert (meta["format"], meta["format_version"], meta["n_cells"], meta["n_bins"], meta["n_nodes"]) == (
        "rpbench-value-model",
        1,
        3,
        2,
        4,
    )
    assert (meta["visited_states"], meta["transitions"]) == (4, 10)
    # the same model gives the same bytes; another value another digest
    assert save_model(hand_model(), tmp_path / "again") == digest
    other = hand_model(values=np.array([[10.0, 11.0], [20.0, 21.0], [30.0, 31.5]]))
    assert save_model(other, tmp_path / "other") != digest


def test_value_at_reads_the_nodes_cell_and_the_clamped_bin():
    model = hand_model()
    nodes = np.array([0, 1, 2, 3, 3, 1])
    t = np.array([0.0, 599.0, 600.0, 1e6, -10.0, 1199.9])
    assert model.value_at(nodes, t).tolist() == [10.0, 20.0, 31.0, 31.0, 30.0, 21.0]
    assert model.n_bins == 2


def test_save_model_refuses_an_existing_folder(saved):
    with pytest.raises(FileExistsError):
        save_model(hand_model(), saved)


def test_save_model_atomically_keeps_a_folder_another_process_finished(tmp_path):
    """The second save into the same place keeps the first folder (same training, same bytes) and leaves
    no staging folder behind."""
    final = tmp_path / "cache" / "key"
    first = save_model_atomically(hand_model(), final)
    before = {p.name: p.read_bytes() for p in final.iterdir()}
    second = save_model_atomically(hand_model(), final)
    assert first == second == model_digest(final)
    assert {p.name: p.read_bytes() for p in final.iterdir()} == before
    assert [p.name for p in final.parent.iterdir()] == ["key"]


def _save_array(folder: Path, name: str, array: np.ndarray, *, fix_digest: bool) -> None:
    np.save(folder / f"{name}.npy", array, allow_pickle=False)
    if fix_digest:  # a consistent edit: model.json names the new array's digest
        _edit_json(folder, lambda m: m["arrays"].__setitem__(name, sha256(folder / f"{name}.npy")))


def _write_bytes(folder: Path, name: str, fn) -> None:
    """``name``.npy replaced by ``fn(its bytes)``, its digest in model.json fixed to match."""
    path = folder / f"{name}.npy"
    path.write_bytes(fn(path.read_bytes()))
    _edit_json(folder, lambda m: m["arrays"].__setitem__(name, sha256(path)))


def _edit_json(folder: Path, fn) -> None:
    meta = json.loads((folder / MODEL_JSON).read_text())
    fn(meta)
    (folder / MODEL_JSON).write_text(json.dumps(meta))


def _flip_a_byte(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[-1] ^= 1
    path.write_bytes(bytes(data))


DAMAGES = {
    "edited values": (
        lambda f: _save_array(f, "values", np.array([[10.0, 11.0], [20.0, 21.0], [30.0, 99.0]]), fix_digest=False),
        "values.npy does not match its digest in model.json (edited or damaged)",
    ),
    "a flipped byte": (lambda f: _flip_a_byte(f / "visits.npy"), "visits.npy does not match its digest"),
    "a missing array": (lambda f: (f / "node_cell.npy").unlink(), "cannot read node_cell.npy"),
    "a missing description": (lambda f: (f / MODEL_JSON).unlink(), "/model.json' does not exist"),
    "not JSON": (lambda f: (f / MODEL_JSON).write_text("{not json"), "/model.json' is not valid JSON"),
    "a JSON list": (lambda f: (f / MODEL_JSON).write_text("[]"), "does not hold a JSON object"),
    "another format": (
        lambda f: _edit_json(f, lambda m: m.__setitem__("format", "pickle")),
        "model.json is not a rpbench-value-model version 1 description",
    ),
    "another version": (
        lambda f: _edit_json(f, lambda m: m.__setitem__("format_version", 2)),
        "model.json is not a rpbench-value-model version 1 description",
    ),
    "no array digests": (lambda f: _edit_json(f, lambda m: m.pop("arrays")), "model.json names no array digests"),
    "a wrong shape": (
        lambda f: _edit_json(f, lambda m: m.__setitem__("n_cells", 4)),
        "its arrays do not have the shapes model.json gives",
    ),
    "a shape that is no number": (
        lambda f: _edit_json(f, lambda m: m.__setitem__("n_bins", "six")),
        "model.json is incomplete (ValueError",
    ),
    "a missing field": (
        lambda f: _edit_json(f, lambda m: m.pop("cell_m")),
        "model.json is incomplete (KeyError: 'cell_m')",
    ),
    "a cell outside the grid": (
        lambda f: _save_array(f, "node_cell", np.array([0, 1, 2, 3]), fix_digest=True),
        "node_cell.npy names cells outside 0..2",
    ),
    "a file that is no array": (
        lambda f: _write_bytes(f, "values", lambda data: b"not an array"),
        "values.npy is not a .npy array (",
    ),
    "a truncated array": (
        lambda f: _write_bytes(f, "visits", lambda data: data[:100]),
        "visits.npy is not a .npy array (",
    ),
    "values that are text": (
        lambda f: _save_array(f, "values", np.full((3, 2), "a"), fix_digest=True),
        "values.npy holds <U1 values, not numbers",
    ),
    "cells that are not integers": (
        lambda f: _save_array(f, "node_cell", np.array([0.0, 1.0, 2.0, 2.0]), fix_digest=True),
        "node_cell.npy holds float64 values, not integers",
    ),
    "a value that is not finite": (
        lambda f: _save_array(f, "values", np.array([[10.0, 11.0], [np.nan, 21.0], [30.0, 31.0]]), fix_digest=True),
        "values.npy holds values that are not finite",
    ),
}


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_a_damaged_model_is_one_line_naming_the_folder(saved, damage):
    edit, fragment = DAMAGES[damage]
    edit(saved)
    with pytest.raises(ParameterError) as info:
        load_model(saved)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"value model {str(saved)!r}"), message
    assert fragment in message, message


def test_a_folder_that_is_not_there(tmp_path):
    with pytest.raises(ParameterError, match="is not a folder \\(train one with `rpbench train vf --out FOLDER`\\)"):
        load_model(tmp_path / "nowhere")
    (tmp_path / "file").write_text("x")
    with pytest.raises(ParameterError, match="is not a folder"):
        load_model(tmp_path / "file")
    with pytest.raises(ParameterError, match="cannot read model.json") as info:
        model_digest(tmp_path / "nowhere")
    assert "\n" not in str(info.value)


def test_a_model_of_another_network_is_refused():
    net = build_scenario("toy", sample=0.1).network
    with pytest.raises(ParameterError, match="vf: the value model was learned on another road network \\(net-hash"):
        hand_model().check_network(net, "vf")
    hand_model(network=net.content_hash).check_network(net, "vf")  # its own network passes
