"""``rpbench replicate``: the --json contract, one-line errors, and ``rpbench check`` on its folder."""

from __future__ import annotations

import json

import pytest

from rpbench.cli import main

CONTRACT = {"engine", "strategy", "date", "pairing_ratio", "total_saving_km", "response_rate"}


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_replicate_json_contract_fast(capsys, data_dir, tmp_path):
    code, out, _ = run_cli(
        capsys,
        "replicate",
        "--data",
        str(data_dir),
        "--date",
        "2017-05-01",
        "--strategies",
        "mb",
        "--no-ablation",
        "--no-rpbench",
        "--json",
        "--out",
        str(tmp_path / "rep"),
    )
    assert code == 0
    runs = json.loads(out)["runs"]
    assert [r["engine"] for r in runs] == ["authors"]
    assert set(runs[0]) >= CONTRACT
    assert runs[0]["response_denominator"] == 530 and runs[0]["vehicles"] == 132
    # The checker audits the authors' run and names what it skips.
    code, out, _ = run_cli(capsys, "check", str(tmp_path / "rep"))
    assert code == 0
    assert "2017-05-01/mb/authors: OK" in out and "[movement] skipped: the authors' vehicles jump" in out


@pytest.mark.slow
def test_replicate_json_contract_full(capsys, data_dir, tmp_path):
    code, out, _ = run_cli(
        capsys,
        "replicate",
        "--data",
        str(data_dir),
        "--date",
        "2017-05-01",
        "--strategies",
        "mb",
        "--json",
        "--out",
        str(tmp_path / "rep"),
    )
    assert code == 0
    runs = json.loads(out)["runs"]
    engines = [r["engine"] for r in runs]
    assert engines[0] == "authors" and engines[-2:] == ["rpbench", "rpbench-peak"] and "authors-all-off" in engines
    assert all(set(r) >= CONTRACT for r in runs)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--strategies", "xyz"], "--strategies 'xyz'"),
        (["--date", "2017-13-01"], "is not of the form YYYY-MM-DD"),
        (["--solver", "nope"], "unknown solver preset 'nope'"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, data_dir, tmp_path, argv, message):
    code, out, err = run_cli(capsys, "replicate", "--data", str(data_dir), *argv, "--out", str(tmp_path / "x"))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and message in err
