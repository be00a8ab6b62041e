"""Options of run, sweep, snapshot and oracle: every bad value is one line, exit status 2, nothing written.

``--opt RUN.KEY=VALUE`` is typed per strategy (unknown keys, values
of the wrong kind and strategies not run are errors); these are regression
tests of that contract on each command that takes options, and of the
oracle's numeric flags.  Every case passes an ``--out`` that must stay
uncreated.
"""

from __future__ import annotations

import pytest

from faults.test_runs_helpers import TOY, assert_nothing_written, assert_one_error, run_cli

SWEEP = ("sweep", "--over", "dt=20,30", *TOY, "--workers", "1")


@pytest.mark.parametrize(
    "argv, message",
    [
        (("run", *TOY, "--strategies", "mb", "--opt", "mb.foo=1"), "mb: unknown option 'foo'"),
        (("run", *TOY, "--strategies", "mb", "--opt", "rtv.c_ko=large"), "run 'rtv' is not in --strategies"),
        (("run", *TOY, "--strategies", "rtv", "--opt", "rtv.c_ko=huge"), "option c_ko = 'huge' must be"),
        (("run", *TOY, "--strategies", "mb", "--opt", "mb"), "expected RUN.KEY=VALUE"),
        (("run", *TOY, "--strategies", "mb", "--opt", "mb.=1"), "expected RUN.KEY=VALUE"),
        (("run", *TOY, "--strategies", "nope"), "unknown strategy 'nope'"),
        (("run", *TOY, "--strategies", "mb,mb"), "names 'mb' twice"),
        (("run", *TOY, "--strategies", "mb", "--solver", "nope"), "unknown solver preset 'nope'"),
        ((*SWEEP, "--strategies", "mb", "--opt", "mb.foo=1"), "mb: unknown option 'foo'"),
        ((*SWEEP, "--strategies", "mb", "--opt", "fl.x=1"), "run 'fl' is not in --strategies"),
        (("sweep", "--over", "dt=", *TOY), "expected NAME=V1,V2,..."),
        (("sweep", "--over", "nope=1,2", *TOY), "unknown sweep parameter 'nope'"),
        (("snapshot", *TOY, "--strategies", "mb", "--opt", "mb.foo=1"), "mb: unknown option 'foo'"),
        (("snapshot", *TOY, "--strategies", "mb", "--rounds", "x"), "--rounds 'x': expected round indices"),
        (("snapshot", *TOY, "--strategies", "mb", "--largest", "0"), "--largest 0 must be >= 1"),
    ],
)
def test_a_bad_option_is_one_line_and_writes_nothing(capsys, tmp_path, argv, message):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, *argv, "--out", out)
    assert_one_error(code, err, message)
    assert stdout == ""
    assert_nothing_written(tmp_path, out)


@pytest.mark.parametrize(
    "argv, message",
    [
        (("--time-limit", "0"), "--time-limit 0.0 must be > 0 seconds"),
        (("--time-limit", "-1"), "--time-limit -1.0 must be > 0 seconds"),
        (("--time-limit", "nan"), "--time-limit nan must be > 0 seconds"),
        (("--unit-m", "0"), "--unit-m 0.0 must be a finite number of metres > 0"),
        (("--unit-m", "inf"), "--unit-m inf must be a finite number of metres > 0"),
        (("--variant", "bound", "--pickup-check"), "--variant bound takes no pair-rule flags"),
        (("--solver", "nope"), "unknown solver preset 'nope'"),
    ],
)
def test_a_bad_oracle_flag_is_one_line_and_writes_no_pairs(capsys, tmp_path, argv, message):
    pairs = tmp_path / "pairs.csv"
    code, stdout, err = run_cli(capsys, "oracle", *TOY, *argv, "--pairs", pairs)
    assert_one_error(code, err, message)
    assert stdout == ""
    assert_nothing_written(tmp_path, pairs)


def test_a_good_option_still_runs(capsys, tmp_path):
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "rtv", "--opt", "rtv.c_ko=large", "--out", out)
    assert code == 0, err
    assert (out / "meta.json").is_file()


#: Every command taking --decision-budget: a run, a multi-day run, a sweep, an evaluation.
BUDGET_COMMANDS = {
    "run": ("run", *TOY, "--strategies", "mb"),
    "run-without-a-scenario": ("run", "--strategies", "mb"),  # fails before the data would be fetched
    "multi-day": ("run", *TOY, "--strategies", "mb", "--dates", "2017-05-01..2017-05-02"),
    "sweep": (*SWEEP, "--strategies", "mb"),
    "evaluate": ("evaluate", "toy-quick", "--workers", "1"),
}


@pytest.mark.parametrize("command", list(BUDGET_COMMANDS))
@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "abc", "1e999", ""])
def test_a_bad_decision_budget_is_one_line_and_writes_nothing(capsys, tmp_path, command, value):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, *BUDGET_COMMANDS[command], f"--decision-budget={value}", "--out", out)
    line = assert_one_error(code, err, f"--decision-budget {value!r} must be a finite number of seconds > 0")
    assert err.strip() == line and stdout == ""
    assert_nothing_written(tmp_path, out)


def test_a_good_decision_budget_notes_each_flagged_run_and_keeps_json_one_object(capsys, tmp_path):
    import json

    out = tmp_path / "out"
    argv = ("run", *TOY, "--strategies", "mb,rtv,oracle1", "--decision-budget", "1e-9", "--json", "--out", out)
    code, stdout, err = run_cli(capsys, *argv)
    assert code == 0, err
    kpis = json.loads(stdout)["kpis"]
    notes = [line for line in err.splitlines() if "decided slower than" in line]
    assert [line.split(": ")[2] for line in notes] == ["mb", "rtv"]  # the offline run has no rounds
    for line in notes:
        run = line.split(": ")[2]
        n = int(kpis[run]["rounds_over_budget"])
        assert f"{n} of {n} rounds decided slower than the 1e-09 s budget (slowest " in line
