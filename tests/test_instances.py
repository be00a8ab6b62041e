"""Snapshot instances: freeze -> load -> the same model -> the same optimum on every preset."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rpbench.backends.presets import load_preset, preset_names
from rpbench.bench.snapshot import take_snapshots
from rpbench.exceptions import ResultsError
from rpbench.model import AssignmentModel, PairingModel, TripPackingModel
from rpbench.model.instances import find_instances, load_instance, save_instance
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


def installed():
    return [n for n in preset_names() if load_preset(n).is_installed()]


@pytest.fixture(scope="module")
def snapshots(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=4), ["mb", "rtv"])
    folder, entries = take_snapshots(spec, tmp_path_factory.mktemp("s") / "snaps", largest=2)
    return folder, entries


def test_snapshot_round_trip_same_optimum_on_every_preset(snapshots):
    folder, entries = snapshots
    assert len(entries) == 4 and (folder / "manifest.json").is_file()
    for entry in entries:
        model, meta = load_instance(folder / entry["file"])
        assert meta["strategy"] == entry["strategy"] and model.size == entry["size"]
        for name in installed():
            preset = load_preset(name)
            backend = preset.adapter()
            if not backend.supports(model.structure):
                continue
            solution = backend.solve(model, preset.options)
            assert model.violations(solution.chosen) == []
            assert solution.objective == meta["objective"], f"{name} on {entry['file']}"


@pytest.mark.parametrize(
    "model",
    [
        AssignmentModel(2, 2, [0, 0, 1, 1], [0, -1, 1, -1], [5, 0, 7, 0], name="a"),
        TripPackingModel(3, 2, [0, 1, 1], [0, 1, 0], [2, -1, 1], [9, 4, 6], name="t"),
        PairingModel(4, [0, 1, 0], [1, 2, 3], [3, 4, 5], objective="cardinality_then_weight", name="p"),
    ],
)
def test_save_load_is_exact(tmp_path, model):
    path = save_instance(tmp_path / model.name, model, {"note": "x"})
    back, meta = load_instance(path)
    assert type(back) is type(model) and meta == {"note": "x"}
    assert np.array_equal(back.values, model.values) and back.unit_m == model.unit_m
    assert np.array_equal(back.incidence().toarray(), model.incidence().toarray())
    if isinstance(model, PairingModel):
        assert back.objective == model.objective


def test_corrupt_snapshot_files(tmp_path):
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"not a zip file at all")
    with pytest.raises(ResultsError, match="corrupt"):
        load_instance(garbage)
    partial = tmp_path / "partial.npz"
    np.savez(
        partial,
        format=np.array("rpbench-instance-1"),
        structure=np.array("assignment"),
        values=np.array([1.0]),
        unit_m=np.array(1e-3),
        name=np.array("x"),
    )
    with pytest.raises(ResultsError, match="corrupt"):
        load_instance(partial)
    bad_index = tmp_path / "bad.npz"
    np.savez(
        bad_index,
        format=np.array("rpbench-instance-1"),
        structure=np.array("pairing"),
        values=np.array([1.0]),
        unit_m=np.array(1e-3),
        name=np.array("x"),
        n_orders=np.array(2),
        col_a=np.array([0]),
        col_b=np.array([7]),
        meta_json=np.array(json.dumps({})),
    )
    with pytest.raises(ResultsError, match="outside"):
        load_instance(bad_index)
    other = tmp_path / "other.npz"
    np.savez(other, something=np.arange(3))
    with pytest.raises(ResultsError, match="not an rpbench instance"):
        load_instance(other)
    with pytest.raises(ResultsError, match="no snapshot instance files"):
        find_instances([tmp_path / "empty"] if (tmp_path / "empty").mkdir() is None else [])
