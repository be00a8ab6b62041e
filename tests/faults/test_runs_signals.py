"""Interrupts: SIGTERM (and Ctrl-C) at any moment leave no half-written results; stale partials are swept.

The CLI turns SIGTERM into an exception in the main process, so the
cleanup of rpbench.results.store.new_results_folder removes the
``.NAME.partial-PID`` folder; the exit status is 143 (128 + 15) with one
line.  Partial folders of processes that died without cleaning up
(SIGKILL) are removed by the next run writing beside them, when old enough.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from faults.test_runs_helpers import TOY, assert_nothing_written, rpbench_process, run_cli
from rpbench.results import store


def test_sigterm_mid_sweep_in_a_child_process_removes_the_partial_folder(tmp_path):
    out = tmp_path / "sweep"
    child = rpbench_process(
        "sweep",
        "--over",
        "dt=10,20,30,40,50,60",
        "--strategies",
        "mb",
        *TOY,
        "--workers",
        "1",
        "--out",
        out,
        cwd=tmp_path,
        env={"RPBENCH_CACHE": str(tmp_path)},
    )
    partial = tmp_path / f".sweep.partial-{child.pid}"
    deadline = time.monotonic() + 60
    while not partial.exists() and child.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert partial.exists(), "the sweep never started writing"
    child.send_signal(signal.SIGTERM)
    stdout, stderr = child.communicate(timeout=60)
    assert child.returncode == 143, stderr
    assert [line for line in stderr.splitlines() if line.startswith("rpbench: ")] == [
        "rpbench: terminated (SIGTERM); nothing half-written was left"
    ]
    assert "Traceback" not in stderr
    assert_nothing_written(tmp_path, out)


def _send_sigterm_to_self(*args, **kwargs):
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(1)  # the handler raises here, at the latest
    raise AssertionError("SIGTERM did not interrupt")


@pytest.fixture
def report_in_this_process(monkeypatch):
    """report.md written by this process, not by the comparison's second one: a signal sent to "self" from it
    must reach the process whose cleanup is under test (the terminal signals the whole group, child too)."""
    monkeypatch.setattr("rpbench.harness.sidecar.idle_core", lambda: False)


def test_sigterm_during_the_final_write_removes_the_partial_folder(
    capsys, tmp_path, monkeypatch, report_in_this_process
):
    monkeypatch.setattr("rpbench.harness.comparison.write_report", _send_sigterm_to_self)
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    assert code == 143
    assert err.splitlines()[-1] == "rpbench: terminated (SIGTERM); nothing half-written was left"
    assert stdout == ""
    assert_nothing_written(tmp_path, out)


def test_sigterm_during_the_simulation_writes_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr("rpbench.sim.simulator.Simulator._round", _send_sigterm_to_self)
    out = tmp_path / "deep" / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    assert code == 143, err
    assert_nothing_written(tmp_path, out, tmp_path / "deep")


def test_a_second_sigterm_does_not_interrupt_the_cleanup(capsys, tmp_path, monkeypatch, report_in_this_process):
    real_rmtree = store.shutil.rmtree

    def rmtree_under_fire(path, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)  # ignored: the first one's cleanup must finish
        real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr("rpbench.harness.comparison.write_report", _send_sigterm_to_self)
    monkeypatch.setattr(store.shutil, "rmtree", rmtree_under_fire)
    out = tmp_path / "out"
    code, _, _ = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    assert code == 143
    assert_nothing_written(tmp_path, out)


def test_the_previous_sigterm_handler_is_restored(capsys, tmp_path):
    before = signal.getsignal(signal.SIGTERM)
    run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", tmp_path / "out")
    assert signal.getsignal(signal.SIGTERM) is before


def test_ctrl_c_during_the_final_write_removes_the_partial_folder(capsys, tmp_path, monkeypatch):
    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("rpbench.harness.comparison.write_report", interrupt)
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    assert code == 130 and err.splitlines()[-1] == "rpbench: interrupted"
    assert_nothing_written(tmp_path, out)


# ---------------------------------------------------------------- stale partial folders
def dead_pid() -> int:
    """The PID of a process that has exited (and been reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def partial(parent, name: str, pid: int, age_s: float):
    folder = parent / f".{name}.partial-{pid}"
    folder.mkdir(parents=True)
    (folder / "kpis.csv").write_text("run,kpi,value\n")
    stamp = time.time() - age_s
    os.utime(folder, (stamp, stamp))
    return folder


@pytest.fixture
def results_parent(tmp_path):
    parent = tmp_path / "runs"
    parent.mkdir()
    return parent


def new_folder_in(parent):
    with store.new_results_folder(parent / "new", "unused") as (tmp, _):
        (tmp / "meta.json").write_text("{}")


def test_an_old_partial_of_a_dead_process_is_removed(results_parent):
    stale = partial(results_parent, "old-run", dead_pid(), age_s=3600)
    new_folder_in(results_parent)
    assert not stale.exists() and (results_parent / "new" / "meta.json").is_file()


def test_an_old_publish_staging_folder_of_a_dead_process_is_removed(results_parent):
    """rpbench publish stages in ``.DEST.partial-PID-XXXX`` (tempfile.mkdtemp): swept like a run's partial."""
    stale = partial(results_parent, "pub", dead_pid(), age_s=3600)
    staging = stale.rename(stale.with_name(f"{stale.name}-k3x_9a2q"))
    new_folder_in(results_parent)
    assert not staging.exists()


def test_a_young_partial_of_a_dead_process_is_kept(results_parent):
    young = partial(results_parent, "young-run", dead_pid(), age_s=10)
    new_folder_in(results_parent)
    assert young.is_dir()


def test_an_old_partial_of_a_live_process_is_kept(results_parent):
    alive = partial(results_parent, "live-run", os.getppid(), age_s=3600)
    new_folder_in(results_parent)
    assert alive.is_dir()


def test_a_link_named_like_a_partial_is_neither_followed_nor_removed(results_parent, tmp_path):
    target = tmp_path / "precious"
    target.mkdir()
    (target / "data.csv").write_text("keep me\n")
    link = results_parent / f".linked.partial-{dead_pid()}"
    link.symlink_to(target)
    os.utime(link, (0, 0), follow_symlinks=False)
    new_folder_in(results_parent)
    assert link.is_symlink() and (target / "data.csv").read_text() == "keep me\n"


def test_folders_not_named_like_partials_are_kept(results_parent):
    pid = dead_pid()
    others = []
    for name in (f"run.partial-{pid}", f".run.partial-{pid}x", ".run.partial-", "results-2017"):
        folder = results_parent / name
        folder.mkdir()
        os.utime(folder, (0, 0))
        others.append(folder)
    new_folder_in(results_parent)
    assert all(f.is_dir() for f in others)
