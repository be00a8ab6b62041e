"""Worker processes of a parallel sweep die with their parent and never die silently.

A sweep over two points with ``--workers 2`` runs each point in a spawned
worker process (rpbench.harness.parallel).  The points solve with
:class:`SleepyHighs`, which marks its worker's PID in a folder and slows
every solve down, so the test knows when both workers are inside a task.
Killing the parent with SIGKILL must leave no worker running; killing a
worker must end the run with one line naming the point and the signal.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from faults.test_runs_helpers import TESTS, TOY, assert_nothing_written, error_lines
from rpbench.backends.highs import HighsBackend
from rpbench.results import store

#: The environment variable naming the folder where :class:`SleepyHighs` marks its workers.
MARKS = "RPBENCH_TEST_WORKER_MARKS"
POINTS = ("dt=10", "dt=30")  # the sweep's points (--over dt=10,30)
#: Generous: two cores shared by several test runs; every wait below ends as soon as its condition holds.
TIMEOUT_S = 120


class SleepyHighs(HighsBackend):
    """HiGHS, 0.5 s slower per model, touching ``$RPBENCH_TEST_WORKER_MARKS/<pid>`` first."""

    name = "sleepy-highs"

    def solve(self, model, options, **kw):
        (Path(os.environ[MARKS]) / str(os.getpid())).touch()
        time.sleep(0.5)
        return super().solve(model, options, **kw)


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, waiting for its parent to reap it, has ended)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    except OSError:  # no /proc here
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def wait_until(condition, what: str) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting until {what}"
        time.sleep(0.05)


def start_sweep(tmp_path: Path, out: Path) -> tuple[subprocess.Popen, list[int]]:
    """The sweep as a child process in its own session (its own process group, as in a terminal), once
    both of its workers are inside a point; returns it and the workers' PIDs."""
    marks = tmp_path / "marks"
    marks.mkdir()
    preset = tmp_path / "sleepy.toml"
    preset.write_text('backend = "faults.test_runs_workers:SleepyHighs"\n[options]\n')
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")]),
        "RPBENCH_CACHE": str(tmp_path),
        MARKS: str(marks),
    }
    argv = ["sweep", "--over", "dt=10,30", "--strategies", "mb", *TOY]
    argv += ["--solver", str(preset), "--workers", "2", "--out", str(out)]
    child = subprocess.Popen(
        [sys.executable, "-m", "rpbench.cli", *argv],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        wait_until(lambda: len(list(marks.iterdir())) == 2 or child.poll() is not None, "both workers solve")
    except AssertionError:
        child.kill()
        raise
    assert child.poll() is None, child.communicate()
    return child, [int(p.name) for p in marks.iterdir()]


def finish(child: subprocess.Popen) -> str:
    """The child's stderr once it and every process holding its pipes have ended."""
    _, stderr = child.communicate(timeout=TIMEOUT_S)
    return stderr


def test_sigkill_of_the_parent_leaves_no_worker_running(tmp_path):
    out = tmp_path / "sweep"
    child, workers = start_sweep(tmp_path, out)
    child.kill()
    wait_until(lambda: not any(alive(pid) for pid in workers), "the workers are gone")
    finish(child)
    assert child.returncode == -signal.SIGKILL
    assert not os.path.lexists(out)
    # a SIGKILL cleans nothing: the parent's partial folder is left for the stale-partial sweep
    assert store.remove_stale_partials(tmp_path, older_than_s=0) == [tmp_path / f".sweep.partial-{child.pid}"]


def test_a_killed_worker_is_one_line_naming_its_point_and_the_signal(tmp_path):
    out = tmp_path / "sweep"
    child, workers = start_sweep(tmp_path, out)
    os.kill(workers[0], signal.SIGKILL)
    stderr = finish(child)
    assert child.returncode == 2, stderr
    assert "Traceback" not in stderr, stderr
    [line] = error_lines(stderr)
    assert "was killed by SIGKILL" in line and f"pid {workers[0]}" in line, line
    assert any(f"running {point} " in line for point in POINTS), line
    assert not any(alive(pid) for pid in workers)
    assert_nothing_written(tmp_path, out)


def test_sigterm_of_the_parent_stops_its_workers(tmp_path):
    out = tmp_path / "sweep"
    child, workers = start_sweep(tmp_path, out)
    child.terminate()
    stderr = finish(child)
    assert child.returncode == 143, stderr
    # One line for the stop; a note of the run itself may come before it (a cache another test's killed
    # process left incomplete is rebuilt with one), but no line per worker.
    said = [
        line for line in stderr.splitlines() if line.startswith("rpbench: ") and not line.startswith("rpbench: note:")
    ]
    assert said == ["rpbench: terminated (SIGTERM); nothing half-written was left"]
    assert not any(alive(pid) for pid in workers)
    assert_nothing_written(tmp_path, out)


def test_ctrl_c_to_the_process_group_is_one_line_not_one_traceback_per_worker(tmp_path):
    """A terminal's Ctrl-C reaches the parent and every worker: the workers leave it to the parent."""
    out = tmp_path / "sweep"
    child, workers = start_sweep(tmp_path, out)
    os.killpg(child.pid, signal.SIGINT)
    stderr = finish(child)
    assert child.returncode == 130, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr, stderr
    assert stderr.splitlines()[-1] == "rpbench: interrupted"
    assert not any(alive(pid) for pid in workers)
    assert_nothing_written(tmp_path, out)
