"""``rpbench evaluate`` under faults: a bad protocol or preset fails before the folder exists, a unit whose
writer died is swept when the evaluation resumes, and SIGINT stops an evaluation (even one started with
SIGINT ignored, as a shell starts a background job) leaving only whole units, which a rerun completes."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from faults.test_runs_helpers import TESTS, assert_one_error, leftovers, run_cli
from rpbench.check import check_tree

PROTOCOL = """
name = "toy-faults"
version = 1
scenario = "{scenario}"
{extra}
seeds = [0, 1, 2, 3]
strategies = ["mb", "bound"]
preset = "{preset}"
metrics = ["total_saving_km"]
[bootstrap]
resamples = 100
"""


def protocol(tmp_path: Path, *, scenario: str = "toy", extra: str = "sample = 0.1", preset: str = "highs") -> Path:
    path = tmp_path / "toy-faults.toml"
    path.write_text(PROTOCOL.format(scenario=scenario, extra=extra, preset=preset))
    return path


def test_an_unknown_preset_fails_before_the_folder_exists(capsys, tmp_path):
    out = tmp_path / "eval"
    code, _, err = run_cli(capsys, "evaluate", protocol(tmp_path, preset="nope"), "--out", out)
    assert_one_error(code, err, "unknown solver preset 'nope'")
    assert not out.exists()


def test_a_day_listed_twice_fails_before_the_folder_exists(capsys, tmp_path, fake_data):
    out = tmp_path / "eval"
    path = protocol(tmp_path, scenario="haikou-peak", extra='dates = "2017-05-01,2017-05-01"\nsample = 0.5')
    code, _, err = run_cli(capsys, "evaluate", path, "--data", fake_data, "--out", out)
    assert_one_error(code, err, "protocol 'toy-faults': dates '2017-05-01,2017-05-01': 2017-05-01 given twice")
    assert not out.exists()


def test_a_unit_whose_writer_died_is_swept_when_the_evaluation_resumes(capsys, tmp_path):
    out = tmp_path / "eval"
    path = protocol(tmp_path)
    assert run_cli(capsys, "evaluate", path, "--out", out, "--workers", "1")[0] == 0
    (out / "seed2").rename(out / f".seed2.partial-{dead_pid()}")  # killed (SIGKILL) just now, mid-write
    code, _, err = run_cli(capsys, "evaluate", path, "--out", out, "--workers", "1")
    assert code == 0, err
    assert leftovers(out) == [] and (out / "seed2" / "kpis.csv").is_file()
    (parent, *_) = check_tree(out)
    assert parent.status == "ok"


def test_sigint_stops_an_evaluation_leaving_whole_units_that_a_rerun_completes(capsys, tmp_path):
    out = tmp_path / "eval"
    path = protocol(tmp_path, extra="sample = 0.5")
    child = subprocess.Popen(
        [sys.executable, "-m", "rpbench.cli", "evaluate", str(path), "--out", str(out), "--workers", "1"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")])},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),  # as a background job starts
    )
    deadline = time.monotonic() + 120
    while not any(p.name.startswith(".seed") for p in out.glob(".*")) and time.monotonic() < deadline:
        time.sleep(0.02)  # until a unit is being written
    child.send_signal(signal.SIGINT)
    _, stderr = child.communicate(timeout=120)
    assert child.returncode == 130, stderr
    assert stderr.splitlines()[-1] == "rpbench: interrupted" and "Traceback" not in stderr
    assert leftovers(out) == []  # only whole units stay
    assert len(list(out.glob("seed*"))) < 4
    code, _, err = run_cli(capsys, "evaluate", path, "--out", out, "--workers", "1")
    assert code == 0, err
    (parent, *_) = check_tree(out)
    assert parent.status == "ok"


def dead_pid() -> int:
    """The pid of a process that has just exited."""
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(done.stdout)
