"""The comparison's second process answers as the in-process steps do, passes errors on and never outlives them."""

from __future__ import annotations

import gzip
import os
from pathlib import Path

import numpy as np
import pytest

from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.harness import sidecar


def _write(folder: Path, name: str) -> None:
    (folder / "report.md").write_text(f"{name} from {os.getpid()}")


def _nothing() -> None:
    pass


@pytest.mark.parametrize("kind", [sidecar.Forked, sidecar.Serial])
def test_offline_runs_then_the_report(kind, tmp_path):
    kwargs = {"warm_up": _nothing} if kind is sidecar.Forked else {}
    side = kind(lambda: {"bound": os.getpid()}, _write, **kwargs)
    try:
        offline = side.offline()
        side.report(tmp_path, "final")
        side.wait()
    finally:
        side.close()
    name, _, pid = (tmp_path / "report.md").read_text().partition(" from ")
    assert name == "final"
    assert (offline["bound"] != os.getpid()) == (kind is sidecar.Forked)
    assert int(pid) == offline["bound"]  # one child does both


def test_start_forks_in_a_top_level_process_with_a_core_idle(monkeypatch):
    monkeypatch.setattr(sidecar, "idle_core", lambda: True)
    side = sidecar.start(lambda: 1, _write, warm_up=_nothing)
    try:
        assert isinstance(side, sidecar.Forked) and side.offline() == 1
    finally:
        side.close()


def test_start_stays_in_process_without_an_idle_core(monkeypatch):
    monkeypatch.setattr(sidecar, "idle_core", lambda: False)
    side = sidecar.start(lambda: os.getpid(), _write, warm_up=_nothing)
    assert isinstance(side, sidecar.Serial) and not isinstance(side, sidecar.Forked)
    assert side.offline() == os.getpid()


def test_an_idle_core_needs_two_cores_and_a_load_below_them(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1})
    monkeypatch.setattr(sidecar, "others_running", lambda: 1.0)  # the other core busy right now
    monkeypatch.setattr(os, "getloadavg", lambda: (0.8, 0.0, 0.0))
    assert sidecar.idle_core()
    monkeypatch.setattr(os, "getloadavg", lambda: (1.5, 0.0, 0.0))
    assert not sidecar.idle_core()
    monkeypatch.setattr(sidecar, "others_running", lambda: 0.2)  # the average holds a load that has ended
    assert sidecar.idle_core()
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0})
    monkeypatch.setattr(os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    assert not sidecar.idle_core()


def test_the_processes_running_now_are_read_from_proc(monkeypatch):
    if not os.path.exists("/proc/loadavg"):
        pytest.skip("no /proc/loadavg here")
    running = sidecar.others_running()
    assert 0.0 <= running < float("inf")
    import builtins

    real_open = builtins.open
    monkeypatch.setattr(builtins, "open", lambda path, *a, **k: real_open(os.devnull, *a, **k))  # unreadable
    assert sidecar.others_running() == float("inf")


def _fail() -> None:
    raise ParameterError("no such oracle")


def test_an_error_of_the_child_is_raised_in_the_parent(tmp_path):
    side = sidecar.Forked(_fail, _write, warm_up=_nothing)
    try:
        with pytest.raises(ParameterError, match="no such oracle"):
            side.offline()
    finally:
        side.close()
    side = sidecar.Forked(lambda: 1, lambda folder, name: _fail(), warm_up=_nothing)
    try:
        side.offline()
        side.report(tmp_path, "x")
        with pytest.raises(ParameterError, match="no such oracle"):
            side.wait()
    finally:
        side.close()


@pytest.mark.parametrize(
    ("offline", "message"),
    [
        (lambda: os._exit(3), "died solving the offline runs"),  # a child that dies is an error
        (lambda: lambda: None, "not passed on"),  # an unpicklable answer is one line
    ],
)
def test_a_child_that_cannot_answer_is_one_error(offline, message):
    side = sidecar.Forked(offline, _write, warm_up=_nothing)
    try:
        with pytest.raises(RpbenchError, match=message):
            side.offline()
    finally:
        side.close()


def test_close_ends_a_child_still_working():
    side = sidecar.Forked(lambda: 1, _write, warm_up=lambda: __import__("time").sleep(60))
    side.offline()
    side.close()
    assert not side._child.is_alive()


def _beside(folder: Path, name: str) -> None:
    (folder / "beside.txt").write_text(f"{name} from {os.getpid()}")


@pytest.mark.parametrize("kind", [sidecar.Forked, sidecar.Serial])
def test_a_part_is_drawn_beside_the_report(kind, tmp_path):
    kwargs = {"warm_up": _nothing} if kind is sidecar.Forked else {}
    side = kind(lambda: os.getpid(), _write, _beside, **kwargs)
    try:
        child = side.offline()
        side.report(tmp_path, "final")
        side.wait()
    finally:
        side.close()
    report_pid = int((tmp_path / "report.md").read_text().split(" from ")[1])
    beside_pid = int((tmp_path / "beside.txt").read_text().split(" from ")[1])
    assert report_pid == child
    assert (beside_pid != report_pid) == (kind is sidecar.Forked)


def test_an_error_beside_the_report_is_raised_in_the_parent(tmp_path):
    side = sidecar.Forked(lambda: 1, _write, lambda folder, name: _fail(), warm_up=_nothing)
    try:
        side.offline()
        side.report(tmp_path, "x")
        with pytest.raises(ParameterError, match="no such oracle"):
            side.wait()
    finally:
        side.close()


def test_the_runs_are_shared_out_once_each_the_child_from_the_back():
    def simulate(index: int) -> tuple[int, int]:
        return index, os.getpid()

    claims = sidecar.Claims(7, [0, 2, 6])
    side = sidecar.Forked(lambda: "offline", _write, warm_up=_nothing, simulate=simulate, claims=claims)
    try:
        assert side.offline() == "offline"
        stolen = side.simulated()  # the parent has claimed nothing yet: the child took every movable run
        parents = [index for index in range(7) if side.claim(index)]
    finally:
        side.close()
    assert sorted(stolen) == [0, 2, 6] and parents == [1, 3, 4, 5]
    assert {pid for _, pid in stolen.values()} != {os.getpid()}
    assert all(stolen[index][0] == index for index in stolen)


def test_the_child_takes_its_runs_before_the_parent_reads_a_large_answer():
    """The offline runs' answer can exceed what the pipe holds; the parent reads it only after its own runs, so
    the child must take and simulate its share first."""
    import time

    claims = sidecar.Claims(3, [1, 2])
    side = sidecar.Forked(lambda: b"x" * 20_000_000, _write, warm_up=_nothing, simulate=lambda i: i, claims=claims)
    try:
        deadline = time.monotonic() + 60.0
        while list(claims._taken) != [sidecar._FREE, sidecar._CHILD, sidecar._CHILD] and time.monotonic() < deadline:
            time.sleep(0.05)
        assert list(claims._taken)[1:] == [sidecar._CHILD, sidecar._CHILD]  # taken while nothing was read
        assert len(side.offline()) == 20_000_000 and side.simulated() == {1: 1, 2: 2}
    finally:
        side.close()


def test_the_child_stops_where_the_parent_has_been():
    claims = sidecar.Claims(4, [1, 3])
    assert claims.take(3, sidecar._PARENT)  # the parent reached the last run first
    side = sidecar.Forked(lambda: None, _write, warm_up=_nothing, simulate=lambda i: i, claims=claims)
    try:
        side.offline()
        assert side.simulated() == {}
        assert side.claim(1)  # the child stopped at run 3 and left run 1
    finally:
        side.close()


def test_an_error_simulating_in_the_child_is_raised_in_the_parent():
    side = sidecar.Forked(
        lambda: None, _write, warm_up=_nothing, simulate=lambda i: _fail(), claims=sidecar.Claims(2, [1])
    )
    try:
        side.offline()
        with pytest.raises(ParameterError, match="no such oracle"):
            side.simulated()
    finally:
        side.close()


def test_serial_keeps_every_run_in_process():
    side = sidecar.Serial(lambda: None, _write)
    assert all(side.claim(index) for index in range(3)) and side.simulated() == {}


def _folder_files(folder: Path) -> dict[str, bytes]:
    """Every file of a results folder but those holding times, the run's date or its folder's name."""
    skip = {"meta.json", "rounds.csv.gz", "report.md", "report.html", "kpis.png", "table.tex", "table.csv"}
    out = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file() and path.name not in skip:
            data = path.read_bytes()
            if path.suffix == ".gz":  # the header holds a time
                data = gzip.decompress(data)
            elif path.suffix == ".npz":  # so do the zip entries
                with np.load(path) as arrays:
                    data = b"".join(name.encode() + arrays[name].tobytes() for name in sorted(arrays.files))
            if path.name == "kpis.csv":  # the timing rows aside
                data = b"\n".join(line for line in data.splitlines() if b"_s," not in line and b"decision" not in line)
            out[str(path.relative_to(folder))] = data
    return out


@pytest.mark.slow
def test_a_comparison_writes_the_same_folder_with_or_without_the_second_process(tmp_path, monkeypatch):
    from rpbench import RunSpec, ScenarioRequest, run_comparison
    from rpbench.harness import comparison

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2), ["np", "mb", "fl", "hindsight", "bound", "oracle1"])
    simulate = comparison.simulate_strategy
    parent, pids = os.getpid(), tmp_path / "pids"

    def slow_parent(scenario, entry, *args, **kwargs):
        """Notes which process simulated each run; the parent starts late, so the child takes its share."""
        if os.getpid() == parent and not pids.exists():
            __import__("time").sleep(3.0)
        with pids.open("a") as f:
            f.write(f"{entry.name} {os.getpid()}\n")
        return simulate(scenario, entry, *args, **kwargs)

    monkeypatch.setattr(comparison, "simulate_strategy", slow_parent)
    folders = {}
    for forked in (True, False):
        monkeypatch.setattr(sidecar, "idle_core", lambda forked=forked: forked)
        folders[forked] = run_comparison(spec, tmp_path / str(forked), progress=False).folder
        if forked:
            by = dict(line.split() for line in pids.read_text().splitlines())
            assert by["hindsight"] != str(parent) and by["mb"] == by["fl"] == str(parent)
    assert _folder_files(folders[True]) == _folder_files(folders[False])
    for folder in folders.values():
        assert {"report.md", "report.html", "kpis.png", "timeline.png"} <= {p.name for p in folder.iterdir()}
