"""``--sample`` on the command line: above 1 a demand multiplier of the synthetic day, refused with one line
(exit status 2, nothing written) by every scenario of real orders."""

from __future__ import annotations

import json
import os

import pytest

from rpbench.cli import main

#: Scenarios of real orders; the last ones need a folder the tests do not have, so the check runs first.
REAL = [
    ("haikou-peak",),
    ("haikou-paper-input",),
    ("haikou-trace",),
    ("manhattan-peak",),
    ("manhattan-day",),
    ("city", "--city", "nowhere"),
]


def _error_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("rpbench: error:")]


@pytest.mark.parametrize("command", ["run", "scenario"])
@pytest.mark.parametrize("scenario", REAL, ids=[r[0] for r in REAL])
def test_real_orders_refuse_a_multiplier_in_one_line(capsys, tmp_path, monkeypatch, fake_data, command, scenario):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    name, *extra = scenario
    data = ["--data", str(fake_data)] if name.startswith("haikou") else []
    if command == "run":
        argv = ["run", "--scenario", name, *extra, "--sample", "4", "--strategies", "mb", "--out", str(out)]
    else:
        argv = ["scenario", name, *extra, "--sample", "4"]
    before = sorted(os.listdir(tmp_path))
    code = main([*argv, *data, "--no-progress"] if command == "run" else [*argv, *data])
    captured = capsys.readouterr()
    assert code == 2
    lines = _error_lines(captured.err)
    assert len(lines) == 1 and captured.err.strip() == lines[0], captured.err
    assert "Traceback" not in captured.err and captured.out == ""
    assert f"--sample 4 is out of range (0 < value <= 1) for scenario '{name}'" in lines[0]
    assert "a sample of real orders cannot exceed them" in lines[0]
    assert sorted(os.listdir(tmp_path)) == before and not out.exists()  # nothing written


def test_the_synthetic_day_takes_a_multiplier(capsys, fake_data):
    assert main(["scenario", "haikou-day", "--sample", "4", "--data", str(fake_data), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["orders"], summary["vehicles"], summary["synthetic"]) == (960, 10, True)  # 4 x 240; 25 per 100
    assert "DEMAND x4" in summary["label"]


@pytest.mark.parametrize("value", ["0", "100.5", "nan"])
def test_the_multiplier_has_a_range(capsys, fake_data, value):
    assert main(["scenario", "haikou-day", "--sample", value, "--data", str(fake_data)]) == 2
    (line,) = _error_lines(capsys.readouterr().err)
    assert f"--sample {value} is out of range (0 < value <= 1, or a demand multiplier up to 100" in line
