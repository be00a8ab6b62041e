"""``artefacts``: a vf run's copied value model is the one meta.json names, intact, and held out from the
folder's scenario.  One clean toy folder (mb and vf, the vf model trained on seed 100: ``model=auto``) is
built per module with the command line; each case tampers with a copy and names the check that fails."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from check.tamper import assert_fails, assert_passes, cli, copy, edit_meta, violations
from rpbench.check import check_tree
from rpbench.check.folder import inputs_digest
from rpbench.cli import main

MODEL = Path("runs") / "vf" / "value-model"


@pytest.fixture(scope="module")
def vf_run(tmp_path_factory) -> Path:
    """``rpbench run --scenario toy --sample 0.4 --strategies mb,vf --out DIR --no-progress``."""
    out = tmp_path_factory.mktemp("vf") / "toy"
    with contextlib.redirect_stdout(io.StringIO()):  # a module fixture has no capsys
        code = main(
            ["run", "--scenario", "toy", "--sample", "0.4", "--strategies", "mb,vf", "--out", str(out), "--no-progress"]
        )
    assert code == 0
    return out


@pytest.fixture
def folder(vf_run, tmp_path) -> Path:
    return copy(vf_run, tmp_path)


def recorded_digest(folder: Path) -> str:
    return json.loads((folder / "meta.json").read_text())["runs"]["vf"]["artefacts"]["value-model"]


def only(folder: Path, *checks: str) -> dict[str, list[str]]:
    """The failed checks are exactly ``checks``."""
    found = violations(folder)
    assert set(found) == set(checks), found
    return found


def reseal(folder: Path) -> None:
    """Make a tampered model consistent again: model.json names its arrays' digests, meta.json names
    model.json's digest, and the inputs digest covers the new run record (a careful forgery)."""
    model = folder / MODEL
    meta = json.loads((model / "model.json").read_text())
    meta["arrays"] = {a: hashlib.sha256((model / f"{a}.npy").read_bytes()).hexdigest() for a in meta["arrays"]}
    (model / "model.json").write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n")
    digest = hashlib.sha256((model / "model.json").read_bytes()).hexdigest()

    def seal(m):
        m["runs"]["vf"]["artefacts"]["value-model"] = digest
        m["inputs_digest"] = inputs_digest(folder, m["params"], m["runs"])

    edit_meta(folder, seal)


def test_the_clean_folder_passes_and_checks_the_copy(vf_run, capsys):
    (found,) = assert_passes(vf_run, capsys)
    vf = next(c for c in found.runs if c.run == "vf")
    assert vf.checked["artefacts"] == 1
    assert "artefacts" not in next(c for c in found.runs if c.run == "mb").checked
    assert hashlib.sha256((vf_run / MODEL / "model.json").read_bytes()).hexdigest() == recorded_digest(vf_run)


def test_an_edited_values_array_fails_artefacts(folder, capsys):
    values = np.load(folder / MODEL / "values.npy")
    values[0, 0] += 1.0
    np.save(folder / MODEL / "values.npy", values)
    found = only(folder, "artefacts")
    digest = recorded_digest(folder)
    assert found["artefacts"] == [
        f"vf: vf/value-model ({digest[:12]}): values.npy does not match its SHA-256 in model.json (edited or damaged)"
    ]
    code, out, _ = cli(["check", str(folder)], capsys)
    assert code == 1 and "vf: FAILED" in out and "[artefacts] 1 violation(s)" in out and "mb: OK" in out


def test_a_deleted_model_copy_fails_artefacts(folder):
    shutil.rmtree(folder / MODEL)
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "missing: the run folder holds no value-model/model.json", run="vf")


def test_a_deleted_array_fails_artefacts(folder):
    (folder / MODEL / "visits.npy").unlink()
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "visits.npy is missing", run="vf")


def test_another_digest_in_meta_json_fails_artefacts_and_the_inputs_digest(folder):
    """meta.json's artefacts are part of the vf run's record, which the inputs digest covers: both fail."""
    edit_meta(folder, lambda m: m["runs"]["vf"]["artefacts"].__setitem__("value-model", "0" * 64))
    only(folder, "artefacts", "inputs-digest")
    assert_fails(folder, "artefacts", "model.json is not the model the run recorded (its SHA-256 differs)", run="vf")
    assert_fails(folder, "inputs-digest", "run 'vf': its options/rules in meta.json are not those of the run")


def test_an_edited_model_json_fails_artefacts(folder):
    path = folder / MODEL / "model.json"
    path.write_text(path.read_text().replace('"discount": 0.9', '"discount": 0.5'))
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "model.json is not the model the run recorded", run="vf")


def test_a_resealed_edit_of_the_arrays_passes_the_digests_but_not_a_bad_shape(folder):
    """The checker recomputes its own hashes, so only a forger who rewrites model.json and meta.json gets
    past them; a copy whose arrays do not fit still fails."""
    values = np.load(folder / MODEL / "values.npy")
    np.save(folder / MODEL / "values.npy", values[:, :-1])
    reseal(folder)
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", f"its arrays are not of the shape {values.shape} model.json gives", run="vf")


def test_a_resealed_array_of_text_fails(folder):
    np.save(folder / MODEL / "values.npy", np.full((36, 6), "a"))
    reseal(folder)
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "values.npy holds <U1 values, not numbers", run="vf")


def test_a_node_cell_array_of_another_network_fails(folder):
    np.save(folder / MODEL / "node_cell.npy", np.zeros(5, dtype=np.int64))
    reseal(folder)
    only(folder, "artefacts")
    assert_fails(
        folder, "artefacts", "node_cell.npy does not give a cell (0..35) to each of the network's 144", run="vf"
    )


def test_a_model_trained_on_the_folders_own_draw_fails(folder):
    """A model whose training runs include the folder's seed and sample is not held out."""
    path = folder / MODEL / "model.json"
    meta = json.loads(path.read_text())
    assert [(r["seed"], r["sample"]) for r in meta["training"]["runs"]] == [(100, 0.4)]
    meta["training"]["runs"].append({"date": None, "seed": 0, "sample": 0.4, "orders": 160})
    path.write_text(json.dumps(meta))
    reseal(folder)
    only(folder, "artefacts")
    assert_fails(
        folder,
        "artefacts",
        "the model was trained on seed 0 at sample 0.4, the draw this folder tests it on",
        run="vf",
    )


def test_a_resealed_forgery_that_changes_nothing_passes(folder):
    """reseal() itself breaks nothing: the tampering tests above fail for what they change."""
    reseal(folder)
    assert_passes(folder)


def test_a_vf_run_without_its_model_record_fails(folder):
    def drop(m):
        m["runs"]["vf"].pop("artefacts")
        m["inputs_digest"] = inputs_digest(folder, m["params"], m["runs"])

    edit_meta(folder, drop)
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "a vf run names no value-model in meta.json", run="vf")


def test_an_artefact_the_checker_does_not_know_fails(folder):
    def add(m):
        m["runs"]["mb"]["artefacts"] = {"lookup-table": "ab" * 32}
        m["inputs_digest"] = inputs_digest(folder, m["params"], m["runs"])

    edit_meta(folder, add)
    only(folder, "artefacts")
    assert_fails(folder, "artefacts", "unknown artefact 'lookup-table': the checker cannot verify it", run="mb")
    assert next(c for c in check_tree(folder)[0].runs if c.run == "vf").ok
