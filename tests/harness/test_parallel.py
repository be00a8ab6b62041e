"""The parallel task runner: serial, a local pool of spawned worker processes, an existing Dask cluster."""

from __future__ import annotations

import dataclasses
import os
import signal
import sys
import time
from pathlib import Path

import pytest

from rpbench.exceptions import ParameterError
from rpbench.harness.parallel import WorkerDiedError, run_tasks


def square(x: int) -> int:
    return x * x


def sleep_or_fail(task: tuple[str, str]) -> None:
    """``("sleep", dir)`` records its pid and sleeps; ``("fail", dir)`` waits for that record, then raises."""
    kind, folder = task
    pid_file = Path(folder) / "sleeper.pid"
    if kind == "sleep":
        pid_file.write_text(str(os.getpid()))
        time.sleep(120)
        return
    while not pid_file.exists():
        time.sleep(0.05)
    raise ValueError("task failed on purpose")


@dataclasses.dataclass(frozen=True)
class Job:
    """A task named like a day or sweep point (by its ``out`` folder): ``sleep`` records its pid and sleeps;
    ``kill`` and ``exit`` wait for that record, then end their worker by SIGKILL or by exit status 3."""

    kind: str
    folder: str
    out: str


def sleep_or_die(job: Job) -> None:
    pid_file = Path(job.folder) / "sleeper.pid"
    if job.kind == "sleep":
        pid_file.write_text(str(os.getpid()))
        time.sleep(120)
        return
    while not pid_file.exists():
        time.sleep(0.05)
    if job.kind == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    os._exit(3)


@pytest.mark.slow
@pytest.mark.parametrize("kind, how", [("kill", "was killed by SIGKILL"), ("exit", "exited with status 3")])
def test_a_dead_worker_is_one_error_naming_its_task_and_the_other_workers_stop(tmp_path, kind, how):
    jobs = [Job("sleep", str(tmp_path), str(tmp_path / "day-1")), Job(kind, str(tmp_path), str(tmp_path / "day-2"))]
    with pytest.raises(WorkerDiedError) as raised:
        run_tasks(sleep_or_die, jobs, workers=2, label="days", progress=False)
    message = str(raised.value)
    assert message.startswith(f"days: the worker process running day-2 {how} (pid "), message
    assert message.endswith("; the other workers were stopped") and "\n" not in message
    with pytest.raises(ProcessLookupError):
        os.kill(int((tmp_path / "sleeper.pid").read_text()), 0)  # terminated and reaped


@pytest.mark.slow
def test_results_come_back_in_task_order():
    assert run_tasks(square, [1, 2, 3], workers=1) == [1, 4, 9]
    assert run_tasks(square, [3, 1, 2, 5], workers=2, progress=False) == [9, 1, 4, 25]
    assert run_tasks(square, []) == []


def test_bad_worker_count_is_a_parameter_error():
    with pytest.raises(ParameterError, match="--workers 0"):
        run_tasks(square, [1], workers=0)


@pytest.mark.slow
def test_a_failing_task_stops_the_other_workers(tmp_path):
    """The failure propagates while another task still runs, and that task's worker is gone by then
    (a caller may delete the results folder the workers write into)."""
    with pytest.raises(ValueError, match="on purpose"):
        run_tasks(sleep_or_fail, [("sleep", str(tmp_path)), ("fail", str(tmp_path))], workers=2, progress=False)
    pid = int((tmp_path / "sleeper.pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # terminated and reaped


def test_scheduler_without_dask_is_one_clear_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # import fails as if not installed
    with pytest.raises(ParameterError, match=r"--scheduler needs Dask.*rpbench\[dask\]"):
        run_tasks(square, [1, 2], scheduler="tcp://127.0.0.1:1")


@pytest.mark.slow
def test_on_an_existing_dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        assert run_tasks(square, [3, 1, 2], scheduler=cluster.scheduler_address, progress=False) == [9, 1, 4]
