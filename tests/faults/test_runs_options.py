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
