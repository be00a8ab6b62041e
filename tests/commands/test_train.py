"""``rpbench train vf``: a model folder that ``--opt vf.model=FOLDER`` loads and the run records by digest;
every bad input is one line, exit status 2, nothing written.  And ``rpbench run`` refuses a vf model
trained on the scenario it would test."""

from __future__ import annotations

import contextlib
import io
import json

import pytest
from faults.test_runs_helpers import assert_nothing_written, assert_one_error, error_lines, run_cli

from rpbench.cli import main
from rpbench.valuefn.model import MODEL_JSON, load_model, model_digest

TOY = ("--scenario", "toy", "--sample", "0.3")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """``rpbench train vf --scenario toy --sample 0.3 --seeds 1,2 --json``: (folder, its JSON summary)."""
    folder = tmp_path_factory.mktemp("train") / "model"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):  # a module fixture has no capsys
        code = main(["train", "vf", *TOY, "--seeds", "1,2", "--out", str(folder), "--json", "--no-progress"])
    assert code == 0
    return folder, json.loads(out.getvalue())


def test_train_writes_a_model_folder_and_describes_it(trained):
    folder, summary = trained
    model, digest = load_model(folder)
    assert summary["model"] == str(folder)
    assert summary["digest"] == digest == model_digest(folder)
    assert summary["training_runs"] == 2
    assert [(r["seed"], r["sample"]) for r in summary["training"]["runs"]] == [(1, 0.3), (2, 0.3)]
    assert summary["training"] == model.training and model.training["scenario"] == "toy"
    assert summary["states"] == model.visits.size == 36 * 6
    assert summary["transitions"] == int(model.visits.sum()) > 0
    assert summary["visited_states"] == int((model.visits > 0).sum())
    assert sorted(p.name for p in folder.parent.iterdir()) == ["model"]  # no staging folder left


def test_a_run_loads_the_folder_and_records_its_digest(trained, tmp_path, capsys):
    """``--opt vf.model=FOLDER``: meta.json names the model's digest, the run folder holds its copy."""
    folder, summary = trained
    out = tmp_path / "run"
    code, stdout, err = run_cli(
        capsys,
        "run",
        *TOY,
        "--strategies",
        "vf",
        "--opt",
        f"vf.model={folder}",
        "--out",
        out,
        "--no-progress",
        "--json",
    )
    assert code == 0, err
    record = json.loads((out / "meta.json").read_text())["runs"]["vf"]
    assert record["artefacts"] == {"value-model": summary["digest"]}
    assert record["options"]["model"] == str(folder)
    copy = out / "runs" / "vf" / "value-model"
    assert {p.name: p.read_bytes() for p in copy.iterdir()} == {p.name: p.read_bytes() for p in folder.iterdir()}
    assert model_digest(copy) == summary["digest"]


def test_the_text_summary_says_how_to_use_the_model(tmp_path, capsys):
    out = tmp_path / "m"
    code, stdout, err = run_cli(capsys, "train", "vf", *TOY, "--out", out, "--no-progress")
    assert code == 0, err
    digest = model_digest(out)
    assert f"value model {digest[:12]}:" in stdout
    assert f"written to {out}  (use: --opt vf.model={out})" in stdout
    assert "trained on 1 runs of toy (seed 100)" in err  # the default seed, held out from the default 0
    assert (out / MODEL_JSON).is_file()


def test_without_out_the_model_goes_below_the_current_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, stdout, err = run_cli(capsys, "train", "vf", *TOY, "--json", "--no-progress")
    assert code == 0, err
    (made,) = (tmp_path / "rpbench-runs").iterdir()
    assert made.name.startswith("vf-model_") and json.loads(stdout)["model"] == str(made)
    load_model(made)


@pytest.mark.parametrize(
    "argv, message",
    [
        (("--opt", "model=x"), "--opt model: give --out instead"),
        (("--opt", "vf.train_dates=2017-05-01"), "--opt train_dates: give --dates instead"),
        (("--opt", "train_seeds=1"), "--opt train_seeds: give --seeds instead"),
        (("--opt", "cell_m=1"), "vf: option cell_m = 1.0 is out of range (50 <= value <= 100000 m)"),
        (("--opt", "discount=1.5"), "vf: option discount = 1.5 is out of range"),
        (("--opt", "method=mc"), "vf: option method = 'mc' must be one of exact, td"),
        (("--opt", "cell_m"), "--opt 'cell_m': expected NAME=VALUE"),
        (("--opt", "cell_m=500", "--opt", "vf.cell_m=600"), "--opt cell_m is given twice"),
        (("--opt", "colour=red"), "vf: unknown option 'colour'"),
        (("--seeds", "x"), "vf: option train_seeds = 'x'"),
        # train has no single --date or --seed (nor abbreviations of --dates, --seeds)
        (("--date", "X"), "--date: a model is trained on several days, give --dates"),
        (("--date", "2017-05-01"), "--date: a model is trained on several days, give --dates"),
        (("--seed", "3"), "--seed: a model is trained on a list of sample seeds, give --seeds"),
        (("--seeds", "-1"), "vf: option train_seeds = -1 is out of range"),
        (("--dates", "2017-05-01"), "--dates: scenario 'toy' has no dates to choose from"),
    ],
)
def test_a_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, argv, message):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "train", "vf", *TOY, *argv, "--out", out, "--no-progress")
    assert_one_error(code, err, message)
    assert stdout == "" and err.count("\n") == 1
    assert_nothing_written(tmp_path, out)


def test_an_existing_out_folder_is_left_as_it_was(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code, stdout, err = run_cli(capsys, "train", "vf", *TOY, "--out", out, "--no-progress")
    assert_one_error(code, err, f"--out {str(out)!r} already exists (a folder)")
    assert stdout == "" and err.count("\n") == 1
    assert [p.name for p in out.iterdir()] == ["keep.txt"] and (out / "keep.txt").read_text() == "mine"
    assert_nothing_written(tmp_path)


def test_run_refuses_a_vf_model_trained_on_its_scenario(tmp_path, capsys):
    """``--opt vf.train_seeds=0`` on seed 0 (the default): one error line after the scenario's label, exit 2,
    no results folder and no model trained."""
    out = tmp_path / "out"
    code, stdout, err = run_cli(
        capsys, "run", "--scenario", "toy", "--strategies", "vf", "--opt", "vf.train_seeds=0", "--out", out,
        "--no-progress",
    )  # fmt: skip
    line = assert_one_error(code, err, "vf: the value model was trained on this scenario")
    assert "(seed 0 is one of its training seeds)" in line
    assert stdout == ""
    assert [x for x in err.splitlines() if x not in error_lines(err)] == [
        "SYNTHETIC toy city (12x12 grid, 400 orders in one hour, seed 0)"
    ]
    assert_nothing_written(tmp_path, out)
