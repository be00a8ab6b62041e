"""The command line: JSON contracts and one-line errors with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from rpbench.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_scenario_json_keys(capsys):
    code, out, _ = run_cli(capsys, "scenario", "toy", "--json")
    assert code == 0
    summary = json.loads(out)
    assert {"orders", "vehicles", "nodes"} <= set(summary)
    assert summary["orders"] == 400 and summary["nodes"] == 144


def test_scenario_haikou_peak_json(capsys, data_dir):
    code, out, _ = run_cli(capsys, "scenario", "haikou-peak", "--date", "2017-05-01", "--json")
    summary = json.loads(out)
    assert (summary["orders"], summary["vehicles"], summary["nodes"]) == (605, 151, 3901)


def test_scenario_text(capsys):
    code, out, _ = run_cli(capsys, "scenario", "toy", "--sample", "0.5")
    assert code == 0 and "orders" in out and "200" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["scenario", "toy", "--sample", "0"], "--sample 0 is out of range (0 < value <= 1, or a demand multiplier"),
        (["scenario", "toy", "--param", "dt_s=0"], "dt_s = 0.0 must be > 0"),
        (["scenario", "toy", "--param", "speed_mps=-8"], "speed_mps = -8.0 must be > 0"),
        (["scenario", "toy", "--param", "foo=1"], "expected NAME=VALUE"),
        (["scenario", "nowhere"], "unknown scenario 'nowhere'"),
        (["scenario", "haikou-peak", "--data", "/no/such/dir"], "does not exist"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("rpbench: error: ")
    assert message in err


def test_date_without_file(capsys, fake_data):
    code, _, err = run_cli(capsys, "scenario", "haikou-peak", "--data", str(fake_data), "--date", "2017-05-02")
    assert code == 2 and "no peak-hour order file for 2017-05-02" in err


#: Registered before the console script runs: printed only if the interpreter's own exit runs.
_ATEXIT = "import atexit, sys; atexit.register(lambda: print('atexit ran', file=sys.stderr)); "


def _console(*args: str, **kwargs) -> subprocess.CompletedProcess:
    """The console script's path: ``entry`` in a process of its own."""
    code = _ATEXIT + "from rpbench.cli import entry; sys.argv[0] = 'rpbench'; entry()"
    streams = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, **kwargs}
    return subprocess.run([sys.executable, "-c", code, *args], text=True, timeout=120, **streams)


def test_the_console_script_ends_at_once_with_its_output_flushed_and_its_status():
    done = _console("scenario", "toy", "--json")
    assert done.returncode == 0 and json.loads(done.stdout)["orders"] == 400
    assert "atexit ran" not in done.stderr  # a success skips the interpreter's teardown
    bad = _console("run", "--sample", "-1")
    assert bad.returncode == 2 and bad.stdout == ""
    # an error or a stop exits the ordinary way, so multiprocessing's exit handler releases a stopped pool's
    # semaphores (its resource tracker would otherwise warn after rpbench's last line)
    [line, ran] = bad.stderr.strip().splitlines()
    assert line.startswith("rpbench: error:") and ran == "atexit ran"
