"""The comparison's second process answers as the in-process steps do, passes errors on and never outlives them."""

from __future__ import annotations

import os
from pathlib import Path

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


def test_start_forks_in_a_top_level_process():
    side = sidecar.start(lambda: 1, _write, warm_up=_nothing)
    try:
        assert isinstance(side, sidecar.Forked) and side.offline() == 1
    finally:
        side.close()


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


def test_a_child_that_dies_is_an_error():
    side = sidecar.Forked(lambda: os._exit(3), _write, warm_up=_nothing)
    try:
        with pytest.raises(RpbenchError, match="offline runs died"):
            side.offline()
    finally:
        side.close()


def test_an_unpicklable_answer_is_one_line():
    side = sidecar.Forked(lambda: lambda: None, _write, warm_up=_nothing)
    try:
        with pytest.raises(RpbenchError, match="not passed on"):
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
