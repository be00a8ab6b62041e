"""The instance library: sets rebuilt bit for bit, verified against their manifests, known values proven."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from faults.test_runs_helpers import assert_one_error, run_cli

from rpbench.backends import load_preset, solve
from rpbench.exceptions import ResultsError
from rpbench.files.digests import arrays_sha256
from rpbench.library.build import build_set
from rpbench.library.export import read_mps_optimum, write_model
from rpbench.library.manifest import MANIFEST, packaged_manifest, verify_folder
from rpbench.library.prove import prove
from rpbench.library.sets import SETS, InstanceSet, instance_set
from rpbench.model.instances import load_instance, load_instances, save_instance
from rpbench.results.solu import read_solu

ROOT = Path(__file__).resolve().parents[2]
COMMITTED_S = ROOT / "instances" / "library" / "S"
SOLU = ROOT / "instances" / "rpbench.solu"


def toy_only() -> InstanceSet:
    """The toy-city part of set S (no data needed)."""
    s = instance_set("S")
    return InstanceSet("S", "S", s.description, sources=tuple(x for x in s.sources if x.scenario == "toy"))


def test_every_set_has_a_reference_manifest_naming_its_files():
    for name in SETS:
        ref = packaged_manifest(name)
        assert ref is not None and ref["set"] == name, name
        files = [e["file"] for e in ref["instances"]]
        assert files and len(set(files)) == len(files)
        assert all(len(e["sha256"]) == 64 and len(e["content_sha256"]) == 64 for e in ref["instances"])


def test_the_committed_s_tier_holds_its_manifests_arrays():
    assert verify_folder(COMMITTED_S, packaged_manifest("S")) == []
    assert (COMMITTED_S / MANIFEST).is_file()


def test_the_toy_part_of_s_is_rebuilt_bit_for_bit(tmp_path):
    folder = tmp_path / "S"
    folder.mkdir()
    built = build_set(toy_only(), folder)
    reference = {e["file"]: e for e in packaged_manifest("S")["instances"]}
    assert len(built["instances"]) == 6
    # The files' bytes are Python's zipfile's too: 3.11.2 (Debian's) writes a zip64 member's header otherwise
    # than 3.11.7, which wrote the committed files; the arrays (content_sha256) must match on any Python.
    same_zipfile = sys.version_info >= (3, 11, 7)
    for entry in built["instances"]:
        want = reference[entry["file"]]
        assert entry["content_sha256"] == want["content_sha256"], entry["file"]
        if same_zipfile:
            assert entry == want, entry["file"]
            assert (folder / entry["file"]).read_bytes() == (COMMITTED_S / entry["file"]).read_bytes()
        else:
            assert {**entry, "sha256": None} == {**want, "sha256": None}, entry["file"]


@pytest.mark.haikou
def test_the_whole_s_tier_is_rebuilt_and_verified(tmp_path, data_dir, capsys):
    out = tmp_path / "S"
    code, stdout, err = run_cli(capsys, "instances", "build", "S", "--out", out, "--data", data_dir, "--no-progress")
    assert code == 0, err
    assert "OK, the 12 instances of set S hold the manifest's arrays (12 of 12 files identical byte for byte)" in stdout


def test_verify_names_a_damaged_a_missing_and_an_extra_file(tmp_path, capsys):
    folder = tmp_path / "S"
    shutil.copytree(COMMITTED_S, folder)
    victim = folder / "toy_s030_seed1_oracle1.npz"
    model, meta = load_instance(victim)
    values = model.values.copy()
    values[0] += 1
    save_instance(
        victim,
        type(model)(
            model.n_orders,
            model.col_a,
            model.col_b,
            values,
            objective=model.objective,
            unit_m=model.unit_m,
            name=model.name,
        ),
        meta,
    )
    (folder / "toy_s030_seed1_mb_round00025.npz").unlink()
    shutil.copy(folder / "toy_s030_seed1_bound.npz", folder / "stray.npz")
    problems = verify_folder(folder, packaged_manifest("S"))
    assert problems == [
        "stray.npz: not in the manifest",
        "toy_s030_seed1_mb_round00025.npz: missing",
        "toy_s030_seed1_oracle1.npz: its arrays differ from the manifest's (content SHA-256)",
    ]
    code, stdout, _ = run_cli(capsys, "instances", "verify", "S", "--dir", folder)
    assert code == 1 and stdout.count("FAILED ") == 3


def test_content_digest_ignores_the_compressor_but_not_the_arrays(tmp_path):
    source = COMMITTED_S / "toy_s030_seed1_bound.npz"
    with np.load(source) as z:
        arrays = {k: z[k] for k in z.files}
    np.savez(tmp_path / "plain.npz", **arrays)  # stored, not deflated, other member times
    assert (tmp_path / "plain.npz").read_bytes() != source.read_bytes()
    assert arrays_sha256(tmp_path / "plain.npz") == arrays_sha256(source)
    arrays["values"] = arrays["values"] + 1
    np.savez(tmp_path / "edited.npz", **arrays)
    assert arrays_sha256(tmp_path / "edited.npz") != arrays_sha256(source)


def test_bad_set_names_and_folders_are_one_line(tmp_path, capsys):
    code, _, err = run_cli(capsys, "instances", "verify", "Q")
    assert_one_error(code, err, "unknown instance set 'Q'")
    code, _, err = run_cli(capsys, "instances", "verify", "M", "--dir", tmp_path / "none")
    assert_one_error(code, err, "does not exist")
    code, _, err = run_cli(capsys, "instances", "build", "S", "--out", tmp_path)
    assert_one_error(code, err, "already exists")


# ------------------------------------------------------------------ known values
def test_the_solu_file_names_only_library_instances_and_its_values_are_the_optima():
    known = read_solu(SOLU)
    names = {e["file"][: -len(".npz")] for name in SETS for e in packaged_manifest(name)["instances"]}
    assert set(known) <= names and len(known) >= 50
    models, _ = load_instances([COMMITTED_S])
    highs = load_preset("highs")
    for model in models:
        entry = known[model.name]
        assert entry.kind == "opt", model.name
        assert solve(model, highs).objective == entry.value, model.name


def test_an_mps_file_read_back_by_highs_reaches_the_solu_optimum(tmp_path):
    known = read_solu(SOLU)
    models, _ = load_instances([COMMITTED_S])
    for model in models:
        path = write_model(model, tmp_path / f"{model.name}.mps", "mps")
        assert read_mps_optimum(path) == known[model.name].value, model.name


def test_two_front_ends_of_one_solver_are_not_independent_proof():
    model, _ = load_instance(COMMITTED_S / "toy_s030_seed1_mb_round00025.npz")
    one = prove(model, [load_preset("highs"), load_preset("scipy")], 30.0)
    assert one.known.kind == "best" and one.algorithms == ("HiGHS",)
    two = prove(model, [load_preset("highs"), load_preset("matching")], 30.0)
    assert two.known.kind == "opt" and two.algorithms == ("HiGHS", "Jonker-Volgenant")
    assert one.known.value == two.known.value


def test_different_proven_optima_are_an_error():
    from rpbench.backends import Preset
    from rpbench.backends.highs import HighsBackend
    from rpbench.model import Status, make_solution

    model, _ = load_instance(COMMITTED_S / "toy_s030_seed1_mb_round00025.npz")

    class Wrong(HighsBackend):
        """Claims that keeping every passenger waiting is optimal."""

        name = "wrong"

        def solve(self, model, options):
            waits = np.flatnonzero(model.col_vehicle < 0)
            first = np.unique(model.col_passenger[waits], return_index=True)[1]
            return make_solution(model, waits[first], Status.OPTIMAL, self.name)

    with pytest.raises(ResultsError, match="prove different optima"):
        prove(model, [load_preset("highs"), Preset.of(Wrong()), load_preset("matching")], 30.0)


# ------------------------------------------------------------------ snapshots of offline models
def test_snapshot_freezes_offline_pairing_models(tmp_path, capsys):
    out = tmp_path / "snap"
    code, stdout, err = run_cli(
        capsys,
        "snapshot",
        "--scenario",
        "toy",
        "--sample",
        "0.3",
        "--seed",
        "1",
        "--strategies",
        "bound,oracle1",
        "--out",
        out,
    )
    assert code == 0, err
    assert "not solved" in stdout
    for run in ("bound", "oracle1"):
        model, meta = load_instance(out / f"toy_{run}.npz")
        frozen, _ = load_instance(COMMITTED_S / f"toy_s030_seed1_{run}.npz")
        assert meta["strategy"] == run and meta["objective"] is None
        assert np.array_equal(model.values, frozen.values) and np.array_equal(model.col_a, frozen.col_a)


def test_snapshot_rounds_of_offline_runs_only_is_one_line(tmp_path, capsys):
    code, _, err = run_cli(
        capsys, "snapshot", "--scenario", "toy", "--strategies", "bound", "--rounds", "3", "--out", tmp_path / "x"
    )
    assert_one_error(code, err, "names only offline runs")


def test_prove_in_isolated_workers_records_a_dead_solver_and_goes_on():
    """``rpbench instances solu`` solves in workers: a solver that dies is an answer, not the end of the file."""
    from bench.crash_backend import Crash

    from rpbench.backends import Preset
    from rpbench.bench import synthetic
    from rpbench.bench.runner import IsolatedWorker
    from rpbench.library.prove import with_time_limit

    presets = [Preset.of(Crash()), load_preset("highs"), load_preset("matching")]
    workers = {p.name: IsolatedWorker(with_time_limit(p, 30.0), 90.0) for p in presets}
    try:
        proof = prove(synthetic.pairing(40, seed=3).renamed("crash"), presets, 30.0, workers=workers)
    finally:
        for w in workers.values():
            w.close()
    assert proof.known.kind == "opt" and proof.algorithms == ("HiGHS", "sparse blossom (PyMatching)")
    assert proof.answers[0].startswith("crash: killed (") and "SIGKILL" in proof.answers[0]


def test_solu_names_each_instance_by_its_file_and_proves_a_shared_one_once(tmp_path, capsys):
    """Tiers share instances (M holds S's peak-hour models): one line per name, never a folder-prefixed one;
    two different files of one name are one error."""
    source = COMMITTED_S / "toy_s030_seed1_mb_round00025.npz"
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        shutil.copy(source, tmp_path / folder / source.name)
    args = ["instances", "solu", tmp_path / "a", tmp_path / "b", "--presets", "matching,highs", "--no-progress"]
    rc, _, err = run_cli(capsys, *args, "--out", tmp_path / "ab.solu")
    assert rc == 0, err
    assert read_solu(tmp_path / "ab.solu") == {source.stem: read_solu(SOLU)[source.stem]}
    other, meta = load_instance(COMMITTED_S / "toy_s030_seed1_rtv_round00056.npz")
    save_instance(tmp_path / "b" / source.name, other, meta)  # same name, other arrays
    assert_one_error(
        *run_cli(capsys, *args, "--out", tmp_path / "x.solu")[::2],
        "two different instances are named 'toy_s030_seed1_mb_round00025'",
    )
    assert not (tmp_path / "x.solu").exists()
