"""Options of every command: every bad value is one line, exit status 2, nothing written, before any work.

``--opt RUN.KEY=VALUE`` is typed per strategy (unknown keys, values
of the wrong kind and strategies not run are errors); these are regression
tests of that contract on each command that takes options, and of every
numeric option's range (:data:`OUT_OF_RANGE` covers each option the parsers
declare: a new one without a case fails :func:`test_every_numeric_option_has_cases`).
Every case passes an ``--out`` that must stay uncreated.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import typing

import pytest

from faults.test_runs_helpers import TOY, assert_nothing_written, assert_one_error, run_cli
from rpbench.cli import build_parser
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.spec import options_class
from rpbench.strategies import STRATEGY_REGISTRY

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
        (("snapshot", *TOY, "--strategies", "mb", "--largest", "0"), "--largest 0 is out of range"),
        (("snapshot", *TOY, "--strategies", "mb", "--rounds", "-1"), "round -1 is out of range"),
        (("snapshot", *TOY, "--strategies", "mb", "--rounds", "3,3"), "gives '3' twice"),
        (("snapshot", *TOY, "--strategies", "mb", "--rounds", "3", "--largest", "2"), "give one of them"),
        (("run", *TOY, "--strategies", "mb", "--workers", "2"), "--workers spreads the days of --dates"),
        (("run", *TOY, "--strategies", "mb", "--param", "dt_s=5", "--param", "dt_s=6"), "dt_s is given twice"),
        ((*SWEEP, "--strategies", "mb", "--param", "dt_s=5"), "--param dt_s conflicts with the sweep over dt"),
        (("sweep", "patience", *TOY, "--param", "planner_patience_s=80"), "conflicts with the sweep over K"),
        (
            ("sweep", "--over", "fl.tau0_s=60,90", *TOY, "--strategies", "fl", "--opt", "fl.tau0_s=30"),
            "--opt 'fl.tau0_s=30' conflicts with the sweep over fl.tau0_s",
        ),
        ((*SWEEP, "--strategies", "mb", "--values", "3,4"), "--values changes a predefined sweep's values"),
        (("sweep", "--over", "dt=20,20", *TOY, "--strategies", "mb"), "20 appears twice; each point once"),
        ((*SWEEP[:-2], "--strategies", "mb", "--scheduler", "not a url"), "is not a Dask scheduler address"),
        ((*SWEEP[:-2], "--strategies", "mb", "--scheduler", "tcp://host:99999"), "its port must be a number"),
        ((*SWEEP[:-2], "--strategies", "mb", "--scheduler", "http://host:8786"), "is not a Dask scheduler address"),
        ((*SWEEP, "--strategies", "mb", "--scheduler", "tcp://host:8786"), "--workers and --scheduler exclude"),
        (("run", *TOY, "--strategies", "fl@tau0_s=60." + "0" * 260), "names the run's folder, at most 255"),
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
        (("--time-limit", "0"), "--time-limit 0 is out of range (0 < value <= 1e+06 s)"),
        (("--time-limit", "nan"), "--time-limit nan is out of range"),
        (("--unit-m", "5000"), "--unit-m 5000 is out of range (1e-06 <= value <= 1 m)"),
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
@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "abc", "1e999", "", "1e9"])
def test_a_bad_decision_budget_is_one_line_and_writes_nothing(capsys, tmp_path, command, value):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, *BUDGET_COMMANDS[command], f"--decision-budget={value}", "--out", out)
    what = "is not a number" if value in ("abc", "") else "is out of range (0 < value <= 86400 s)"
    line = assert_one_error(code, err, f"--decision-budget {value or repr(value)} {what}")
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


# ------------------------------------------------------------------ numeric ranges
#: How each command with numeric options is called (cheap, toy, writing to OUT), and where it writes.
BASE = {
    "run": ("run", *TOY, "--strategies", "mb", "--out", "OUT"),
    "run-dates": ("run", *TOY, "--strategies", "mb", "--dates", "2017-05-01..2017-05-02", "--out", "OUT"),
    "sweep": (*SWEEP, "--strategies", "mb", "--out", "OUT"),
    "snapshot": ("snapshot", *TOY, "--strategies", "mb", "--out", "OUT"),
    "scenario": ("scenario", "toy", "--sample", "0.1"),
    "oracle": ("oracle", *TOY, "--pairs", "OUT"),
    "bench": ("bench", "--synthetic", "--sizes", "tiny", "--csv", "OUT"),
    "predict": ("predict", "--validate-fcfs", "--offline", "--out", "OUT"),
    "evaluate": ("evaluate", "toy-quick", "--out", "OUT"),
    "train": ("train", "vf", *TOY, "--out", "OUT"),
}
_ANY = ["-1", "1e300", "nan", "inf", "-inf", "abc"]
#: (command, option) -> values out of its range (0 too where 0 is out).  The old behaviour of each is in
#: the change's report; every one now ends the same way.
OUT_OF_RANGE: dict[tuple[str, str], list[str]] = {
    ("train", "--sample"): ["0", "1.5", *_ANY],
    ("bench", "--memory-limit"): ["0", "1e5", *_ANY],
    ("bench", "--shift"): ["3601", *_ANY],
    ("run", "--sample"): ["0", "1.5", *_ANY],
    ("run", "--seed"): ["4294967296", "2.5", *_ANY],
    ("run", "--decision-budget"): ["0", "86401", *_ANY],
    ("run-dates", "--workers"): ["0", "1025", "1e11", *_ANY],
    ("sweep", "--sample"): ["0", *_ANY],
    ("sweep", "--seed"): ["1e11", *_ANY],
    ("sweep", "--workers"): ["0", "1e11", *_ANY],
    ("sweep", "--decision-budget"): ["0", *_ANY],
    ("snapshot", "--sample"): ["0", *_ANY],
    ("snapshot", "--seed"): ["1e11", *_ANY],
    ("snapshot", "--largest"): ["0", "1e11", *_ANY],
    ("scenario", "--sample"): ["0", *_ANY],
    ("scenario", "--seed"): ["1e11", *_ANY],
    ("oracle", "--sample"): ["0", *_ANY],
    ("oracle", "--seed"): ["1e11", *_ANY],
    ("oracle", "--time-limit"): ["0", "1e7", *_ANY],
    ("oracle", "--unit-m"): ["0", "5000", "1e-9", *_ANY],
    ("bench", "--seed"): ["1e11", *_ANY],
    ("bench", "--time-limit"): ["0", "1e7", *_ANY],
    ("bench", "--hard-timeout"): ["0", "1e7", *_ANY],
    ("bench", "--repeat"): ["0", "101", "1e11", "2.5", *_ANY],
    ("predict", "--tau0"): ["86401", *_ANY],
    ("predict", "--hours"): ["0", "1e12", *_ANY],
    ("predict", "--min-samples"): ["0", "1e11", *_ANY],
    ("predict", "--seed"): ["1e11", *_ANY],
    ("evaluate", "--workers"): ["0", "1e11", *_ANY],
    ("evaluate", "--decision-budget"): ["0", *_ANY],
}
#: Commands whose parser declares a numeric option -> the BASE entries that call them.
COMMAND_OF = {key: BASE[key][0] for key in BASE}
CASES = [(cmd, flag, value) for (cmd, flag), values in OUT_OF_RANGE.items() for value in values]


def _numbers(parser: argparse.ArgumentParser) -> dict[str, dict[str, tuple]]:
    """Sub-command -> its numeric options (``add_number_arg``'s registry), for every sub-command."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {name: dict(p.get_default("numbers_") or {}) for name, p in sub.choices.items()}


def test_every_numeric_option_has_cases():
    """No argparse number parser is left (its errors are a usage block), and each numeric option of every
    command has out-of-range cases here."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        assert not [a.option_strings for a in p._actions if a.type in (int, float)], name
    declared = {(name, flag) for name, numbers in _numbers(parser).items() for flag, _ in numbers.values()}
    covered = {(COMMAND_OF[cmd], flag) for cmd, flag in OUT_OF_RANGE}
    assert declared == covered


@pytest.mark.parametrize("command, flag, value", CASES, ids=[f"{c}{f}={v}" for c, f, v in CASES])
def test_a_number_out_of_range_is_one_line_before_any_work(capsys, tmp_path, monkeypatch, command, flag, value):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    argv = [str(out) if a == "OUT" else a for a in BASE[command]]
    code, stdout, err = run_cli(capsys, *argv, f"{flag}={value}")
    line = assert_one_error(code, err, f"{flag} {value} is ")
    assert "is out of range (" in line or "is not a number (" in line
    assert err.strip() == line and stdout == ""  # no progress line, no scenario label: nothing ran
    assert_nothing_written(tmp_path, out)
    assert not (tmp_path / "cache").exists()  # no cache was built


@pytest.mark.parametrize(
    "opt, message",
    [
        ("fl.tau0_s=1e300", "fl: option tau0_s = 1e+300 is out of range (0 <= value <= 86400 s)"),
        ("fl.tau0_s=60,1e9", "fl: option tau0_s = 1000000000.0 is out of range"),
        ("fl.tau0_s=-1", "fl: option tau0_s = -1.0 is out of range"),
        ("fl.mean_pickup_m=1e7", "fl: option mean_pickup_m = 10000000.0 is out of range (0 <= value <= 1e+06 m)"),
        ("rtv.c_ko=-5", "rtv: option c_ko = -5.0 is out of range (0 <= value <= 1e+06 m)"),
        ("rtv.c_ko=1e300", "rtv: option c_ko = 1e+300 is out of range"),
        ("rtv.rv_top_k=0", "rtv: option rv_top_k = 0 is out of range (an integer 1 <= value <= 1000000)"),
        ("rtv.rv_top_k=10000000", "rtv: option rv_top_k = 10000000 is out of range"),
    ],
)
def test_a_strategy_option_out_of_range_is_one_line(capsys, tmp_path, opt, message):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "fl,rtv", "--opt", opt, "--out", out)
    assert err.strip() == assert_one_error(code, err, message) and stdout == ""
    assert_nothing_written(tmp_path, out)


def test_a_sweep_over_an_option_out_of_range_is_one_line(capsys, tmp_path):
    out = tmp_path / "out"
    argv = ("sweep", "--over", "fl.tau0_s=60,1e300", *TOY, "--strategies", "fl", "--out", out)
    code, stdout, err = run_cli(capsys, *argv)
    assert err.strip() == assert_one_error(code, err, "option tau0_s = 1e+300 is out of range") and stdout == ""
    assert_nothing_written(tmp_path, out)


def _numeric(kind) -> bool:
    """Whether a declared option type takes a number (``float | None``, ``tuple[float, ...]``)."""
    return kind in (int, float) or any(_numeric(m) for m in typing.get_args(kind) if m is not Ellipsis)


@pytest.mark.parametrize("name", [*STRATEGY_REGISTRY, *ORACLE_RUNS])
def test_every_numeric_strategy_option_declares_a_range(name):
    cls = options_class(name)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if _numeric(hints[f.name]):
            bounds = f.metadata.get("range")
            assert bounds is not None and math.isfinite(bounds.high), f"{name}.{f.name} has no sane range"


# --------------------------------------------------- names found before any simulation
def test_a_repeated_date_fails_before_any_simulation(capsys, tmp_path, two_day_data):
    out = tmp_path / "out"
    argv = ("run", "--scenario", "haikou-peak", "--data", two_day_data, "--strategies", "mb", "--workers", "1")
    code, stdout, err = run_cli(capsys, *argv, "--dates", "2017-05-01,2017-05-02,2017-05-01", "--out", out)
    line = assert_one_error(code, err, "--dates '2017-05-01,2017-05-02,2017-05-01' gives '2017-05-01' twice")
    assert err.strip() == line and stdout == ""  # not even the "running 3 days" note
    assert_nothing_written(tmp_path, out)


@pytest.mark.parametrize(
    "argv",
    [
        ("run", *TOY, "--strategies", "mb"),
        ("run", *TOY, "--strategies", "mb", "--dates", "2017-05-01..2017-05-02"),
        (*SWEEP, "--strategies", "mb"),
        ("snapshot", *TOY, "--strategies", "mb"),
        ("evaluate", "toy-quick", "--workers", "1"),
    ],
    ids=["run", "run-dates", "sweep", "snapshot", "evaluate"],
)
@pytest.mark.parametrize("size", [240, 256, 300])
def test_an_over_long_out_name_fails_before_any_simulation(capsys, tmp_path, argv, size):
    """Its staging name ``.NAME.partial-PID`` must fit NAME_MAX (255 bytes) too."""
    out = tmp_path / ("x" * size)
    code, stdout, err = run_cli(capsys, *argv, "--out", out)
    line = assert_one_error(code, err, "--out: the ", " bytes")
    assert err.strip() == line and stdout == ""
    assert_nothing_written(tmp_path, out)


def test_an_over_long_out_path_fails_before_any_simulation(capsys, tmp_path):
    out = tmp_path.joinpath(*["y" * 200] * 21)  # each name fits, the path exceeds PATH_MAX (4096)
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    line = assert_one_error(code, err, "the paths would exceed the file system's")
    assert err.strip() == line and stdout == ""
    assert not (tmp_path / ("y" * 200)).exists()


def test_a_long_out_name_that_fits_still_runs(capsys, tmp_path):
    out = tmp_path / ("z" * 230)
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    assert code == 0, err
    assert (out / "meta.json").is_file()


# ------------------------------------------------------------------ oracle rounding
def test_the_oracle_states_a_proven_rounding_slack(capsys, tmp_path):
    """The saving found at a coarse unit is within the stated slack of the (near) unrounded optimum."""
    import json

    found = {}
    for unit in ("1e-6", "1"):
        code, stdout, err = run_cli(capsys, "oracle", "--scenario", "toy", "--unit-m", unit, "--json")
        assert code == 0, err
        found[unit] = json.loads(stdout)
    for variant in ("oracle1", "oracle2"):
        fine, coarse = found["1e-6"][variant], found["1"][variant]
        assert coarse["unit_m"] == 1.0 and coarse["rounding_slack_m"] >= 0
        assert fine["rounding_slack_m"] < 0.01
        gap_m = (fine["total_saving_km"] - coarse["total_saving_km"]) * 1000
        assert gap_m <= coarse["rounding_slack_m"] + fine["rounding_slack_m"] + 1e-6
    code, stdout, err = run_cli(capsys, "oracle", "--scenario", "toy", "--variant", "1")
    assert code == 0 and "proven rounding slack" in stdout
