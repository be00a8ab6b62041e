"""Solver limits: a round or oracle stopped before its optimum is proven is never a silent result.

Without ``--strict`` the run succeeds, says so in one note line per run on
stderr and marks the run in the terminal table and in report.md; with
``--strict`` it is one error line, exit status 2, and nothing is written.
"""

from __future__ import annotations

import json
import re

import pandas as pd
import pytest

from faults.test_runs_helpers import (
    TOY,
    assert_nothing_written,
    assert_one_error,
    preset_file,
    run_cli,
)
from rpbench.results.read import unproven_runs


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    """Failed-round dumps of strict runs land in this test's own cache, not the shared one."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


@pytest.fixture
def unproven(tmp_path) -> str:
    return preset_file(tmp_path, "UnprovenHighs")


def notes(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("rpbench: note:")]


def test_unproven_rounds_give_one_note_line_per_run_and_marked_columns(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "np,mb", "--solver", unproven, "--out", out)
    assert code == 0, err
    rounds = pd.read_csv(out / "rounds.csv.gz")
    n = rounds.groupby("run").size()
    assert notes(err) == [
        f"rpbench: note: NP {n['np']} of {n['np']} rounds ended unproven (time_limit {n['np']}); its numbers are "
        "not proven optimal (--strict makes this an error)",
        f"rpbench: note: MB {n['mb']} of {n['mb']} rounds ended unproven (time_limit {n['mb']}); its numbers are "
        "not proven optimal (--strict makes this an error)",
    ]
    header = next(line for line in stdout.splitlines() if line.startswith("Metric"))
    assert header.split()[-2:] == ["NP*", "MB*"]
    assert "* not proven optimal" in stdout


def test_the_report_marks_unproven_columns_and_says_why(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    assert run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--out", out)[0] == 0
    report = (out / "report.md").read_text()
    assert "| Metric | MB\\* |" in report
    assert re.search(
        r"\\\* \*\*Not proven optimal\.\*\* MB: (\d+) of \1 rounds ended unproven \(time_limit \1\)", report
    )
    assert "--strict" in report


def test_partly_unproven_rounds_are_counted_by_status(capsys, tmp_path):
    half = preset_file(tmp_path, "HalfProvenHighs")
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", half, "--out", out)
    assert code == 0, err
    status = pd.read_csv(out / "rounds.csv.gz")["status"]
    bad = int((status == "feasible").sum())
    assert 0 < bad < len(status)
    assert notes(err) == [
        f"rpbench: note: MB {bad} of {len(status)} rounds ended unproven (feasible {bad}); its "
        "numbers are not proven optimal (--strict makes this an error)"
    ]


def test_a_proven_run_has_no_note_and_no_mark(capsys, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--strict", "--out", out)
    assert code == 0, err
    assert notes(err) == [] and "*" not in stdout
    assert unproven_runs(out) == {}
    assert "Not proven optimal" not in (out / "report.md").read_text()


def test_strict_run_fails_at_the_first_unproven_round_and_writes_nothing(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    code, stdout, err = run_cli(
        capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--strict", "--out", out
    )
    assert_one_error(code, err, "mb round", "stopped with status time_limit, not proven optimal (--strict)")
    assert stdout == ""
    assert_nothing_written(tmp_path, out)


def test_strict_run_saves_the_unproven_round_for_rpbench_bench(capsys, tmp_path, unproven):
    code, _, err = run_cli(
        capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--strict", "--out", tmp_path / "out"
    )
    line = assert_one_error(code, err)
    [dump] = (tmp_path / "cache" / "failed-rounds").glob("mb-round*.npz")
    assert str(dump) in line


def test_strict_fails_on_an_unproven_oracle_before_writing(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    code, _, err = run_cli(
        capsys, "run", *TOY, "--strategies", "mb,oracle1", "--oracle-solver", unproven, "--strict", "--out", out
    )
    assert_one_error(code, err, "Oracle-1 (solver preset 'unprovenhighs') stopped with status time_limit", "(--strict)")
    assert_nothing_written(tmp_path, out)


def test_an_unproven_oracle_is_noted_and_marked_alone(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    code, stdout, err = run_cli(
        capsys, "run", *TOY, "--strategies", "mb,oracle1", "--oracle-solver", unproven, "--out", out
    )
    assert code == 0, err
    assert notes(err) == [
        "rpbench: note: Oracle-1 stopped with status time_limit (gap unknown); its numbers are "
        "not proven optimal (--strict makes this an error)"
    ]
    header = next(line for line in stdout.splitlines() if line.startswith("Metric"))
    assert header.split()[-2:] == ["MB", "Oracle-1*"]
    assert "Oracle-1\\*" in (out / "report.md").read_text()


def test_a_time_limited_upper_bound_is_marked(capsys, tmp_path):
    """The real solver: HiGHS stopped by a 1 µs time limit on the bound's matching MIP."""
    tiny = tmp_path / "tiny.toml"
    tiny.write_text('backend = "highs"\n[options]\ntime_limit_s = 1e-6\n')
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "bound", "--solver", tiny, "--out", out)
    assert code == 0, err
    # HiGHS may or may not have a dual bound by then: the gap is a number or unknown
    [(run, why)] = unproven_runs(out).items()
    assert run == "bound" and re.fullmatch(r"stopped with status time_limit \(gap (unknown|[0-9.e+-]+)\)", why)
    assert notes(err) == [
        f"rpbench: note: Upper bound {why}; its numbers are not proven optimal (--strict makes this an error)"
    ]


def test_json_output_stays_one_object_and_names_the_unproven_runs(capsys, tmp_path, unproven):
    code, stdout, err = run_cli(
        capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--json", "--out", tmp_path / "out"
    )
    assert code == 0, err
    doc = json.loads(stdout)
    assert list(doc["unproven"]) == ["mb"] and "rounds ended unproven" in doc["unproven"]["mb"]
    assert len(notes(err)) == 1


def test_rerendering_a_report_keeps_the_marks(capsys, tmp_path, unproven):
    out = tmp_path / "out"
    assert run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--out", out)[0] == 0
    (out / "report.md").unlink()
    code, stdout, err = run_cli(capsys, "report", out)
    assert code == 0, err
    assert "MB\\*" in stdout and "Not proven optimal" in stdout


def test_oracle_command_notes_and_marks_an_unproven_oracle(capsys, tmp_path, unproven):
    code, stdout, err = run_cli(capsys, "oracle", *TOY, "--variant", "1", "--solver", unproven)
    assert code == 0, err
    assert notes(err) == [
        "rpbench: note: Oracle-1 stopped with status time_limit (gap unknown); its value is not "
        "proven optimal (--strict makes this an error)"
    ]
    assert "Oracle-1 (unprovenhighs)*" in stdout and "* not proven optimal" in stdout


def test_oracle_command_strict_fails_and_writes_no_pairs(capsys, tmp_path, unproven):
    pairs = tmp_path / "pairs.csv"
    code, stdout, err = run_cli(capsys, "oracle", *TOY, "--solver", unproven, "--strict", "--pairs", pairs)
    assert_one_error(code, err, "Oracle-1 (solver preset 'unprovenhighs') stopped with status time_limit")
    assert stdout == ""
    assert_nothing_written(tmp_path, pairs)


def test_oracle_command_strict_with_a_real_time_limit(capsys, tmp_path):
    code, _, err = run_cli(
        capsys, "oracle", *TOY, "--variant", "bound", "--solver", "highs", "--time-limit", "1e-6", "--strict"
    )
    assert_one_error(
        code, err, "Upper bound (solver preset 'highs') stopped with status time_limit", "not proven optimal (--strict)"
    )


def test_sweep_notes_every_unproven_run_of_every_point(capsys, tmp_path, unproven):
    out = tmp_path / "sweep"
    code, _, err = run_cli(
        capsys,
        "sweep",
        "--over",
        "dt=20,30",
        "--strategies",
        "mb",
        *TOY,
        "--solver",
        unproven,
        "--workers",
        "1",
        "--out",
        out,
    )
    assert code == 0, err
    assert [line.split(" rounds")[0].split(" ")[2:4] for line in notes(err)] == [["dt=20:", "MB"], ["dt=30:", "MB"]]
    assert "MB\\*" in (out / "dt=20" / "report.md").read_text()


def test_strict_sweep_fails_and_leaves_no_sweep_folder(capsys, tmp_path, unproven):
    out = tmp_path / "sweep"
    code, _, err = run_cli(
        capsys,
        "sweep",
        "--over",
        "dt=20,30",
        "--strategies",
        "mb",
        *TOY,
        "--solver",
        unproven,
        "--workers",
        "1",
        "--strict",
        "--out",
        out,
    )
    assert_one_error(code, err, "not proven optimal (--strict)")
    assert_nothing_written(tmp_path, out)


def test_strict_mode_does_not_leak_into_the_next_command(capsys, tmp_path, unproven):
    run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--strict", "--out", tmp_path / "a")
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", unproven, "--out", tmp_path / "b")
    assert code == 0 and len(notes(err)) == 1
