"""Output paths and OS errors: one line, exit status 2, checked before any work, nothing half-written.

``--out`` of run / sweep / snapshot (a results folder) must not exist, not
even as a dangling link, and its nearest existing parent must be a folder
that takes new folders; file outputs (``report --out``, ``predict --out``,
``oracle --pairs``, ``bench --csv``) need an existing folder.  An OSError
while writing becomes one line naming the path, and whatever was staged
is removed.
"""

from __future__ import annotations

import errno
import os

import pytest

from faults.test_runs_helpers import (
    TOY,
    assert_nothing_written,
    assert_one_error,
    leftovers,
    read_only_folder,
    run_cli,
)
from rpbench.cli import os_error_line

MB = ("--strategies", "mb")


@pytest.fixture
def a_file(tmp_path):
    path = tmp_path / "a-file"
    path.write_text("not a folder\n")
    return path


@pytest.fixture
def no_simulation(monkeypatch):
    """A bad --out must fail before any simulation: simulating is an error here."""

    def refuse(*args, **kwargs):
        raise AssertionError("simulated despite a bad --out")

    monkeypatch.setattr("rpbench.harness.comparison.simulate_strategy", refuse)
    monkeypatch.setattr("rpbench.bench.snapshot.simulate_strategy", refuse)


@pytest.fixture
def toy_run(capsys, tmp_path):
    """A small proven results folder."""
    folder = tmp_path / "run"
    assert run_cli(capsys, "run", *TOY, *MB, "--out", folder)[0] == 0
    return folder


# ------------------------------------------------------------ results folders, checked up front
@pytest.mark.parametrize(
    "command",
    [
        ("run", *TOY, *MB),
        ("sweep", "--over", "dt=20,30", *MB, *TOY, "--workers", "1"),
        ("snapshot", *TOY, *MB),
    ],
)
def test_out_under_a_file_fails_before_simulating(capsys, tmp_path, a_file, no_simulation, command):
    out = a_file / "out"
    code, stdout, err = run_cli(capsys, *command, "--out", out)
    assert_one_error(code, err, f"--out '{out}': '{a_file}' is not a folder")
    assert stdout == "" and a_file.read_text() == "not a folder\n"
    assert_nothing_written(tmp_path)


@pytest.mark.parametrize(
    "command", [("run", *TOY, *MB), ("sweep", "--over", "dt=20", *MB, *TOY), ("snapshot", *TOY, *MB)]
)
def test_out_under_proc_fails_before_simulating(capsys, no_simulation, command):
    code, _, err = run_cli(capsys, *command, "--out", "/proc/rpbench-test/out")
    assert_one_error(code, err, "--out '/proc/rpbench-test/out': cannot create a folder in '/proc'")
    assert not os.path.lexists("/proc/rpbench-test")


def test_out_deep_under_a_file_fails(capsys, tmp_path, a_file, no_simulation):
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", a_file / "x" / "y" / "out")
    assert_one_error(code, err, f"'{a_file}' is not a folder")


def test_out_an_existing_file_is_never_overwritten(capsys, tmp_path, a_file, no_simulation):
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", a_file)
    assert_one_error(code, err, "already exists (a file); rpbench never overwrites results")
    assert a_file.read_text() == "not a folder\n"


def test_out_an_existing_folder_is_never_overwritten(capsys, toy_run, no_simulation):
    before = sorted(p.name for p in toy_run.iterdir())
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", toy_run)
    assert_one_error(code, err, "already exists (a folder); rpbench never overwrites results")
    assert sorted(p.name for p in toy_run.iterdir()) == before


def test_out_a_dangling_link_is_taken(capsys, tmp_path, no_simulation):
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "nowhere")
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", link)
    assert_one_error(code, err, "already exists (a dangling symbolic link)")
    assert link.is_symlink() and not (tmp_path / "nowhere").exists()


def test_out_in_a_read_only_folder_fails_before_simulating(capsys, tmp_path, no_simulation):
    locked = read_only_folder(tmp_path / "locked")
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", locked / "out")
    assert_one_error(code, err, f"cannot create a folder in '{locked}'")
    assert list(locked.iterdir()) == []


def test_the_default_place_is_checked_too(capsys, tmp_path, monkeypatch, no_simulation):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rpbench-runs").write_text("a file where the runs folder goes\n")
    code, _, err = run_cli(capsys, "run", *TOY, *MB)
    assert_one_error(code, err, "the default results folder ./rpbench-runs", "is not a folder")


def test_missing_parents_are_created_on_success(capsys, tmp_path):
    out = tmp_path / "a" / "b" / "out"
    assert run_cli(capsys, "run", *TOY, *MB, "--out", out)[0] == 0
    assert (out / "meta.json").is_file() and leftovers(tmp_path) == []


# ------------------------------------------------------------ errors while writing
def _raise(exc):
    def fail(folder, *args, **kwargs):
        raise exc(folder) if callable(exc) else exc

    return fail


def test_a_full_disk_while_writing_is_one_line_and_leaves_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(
        "rpbench.harness.comparison.write_report", _raise(OSError(errno.ENOSPC, "No space left on device"))
    )
    out = tmp_path / "new" / "deeper" / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, *MB, "--out", out)
    assert_one_error(code, err, f"cannot write results folder '{out}' (No space left on device); nothing was written")
    assert stdout == ""
    assert_nothing_written(tmp_path, out, tmp_path / "new")  # the parents it created are gone too


def test_a_write_error_names_the_file_inside_the_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(
        "rpbench.harness.comparison.write_report",
        _raise(lambda folder: PermissionError(errno.EACCES, "Permission denied", str(folder / "report.md"))),
    )
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", out)
    assert_one_error(code, err, f"cannot write results folder '{out}' (report.md: Permission denied)")
    assert_nothing_written(tmp_path, out)


def test_a_folder_appearing_at_out_during_the_run_is_not_overwritten(capsys, tmp_path, monkeypatch):
    out = tmp_path / "out"

    def squatter(folder, *args, **kwargs):
        out.mkdir()  # another run took the name meanwhile

    monkeypatch.setattr("rpbench.harness.comparison.write_report", squatter)
    code, _, err = run_cli(capsys, "run", *TOY, *MB, "--out", out)
    assert_one_error(code, err, "appeared while this run was writing it")
    assert out.is_dir() and list(out.iterdir()) == [] and leftovers(tmp_path) == []


def test_an_unforeseen_os_error_is_still_one_line_naming_the_path(capsys, monkeypatch):
    def handler(args):
        raise PermissionError(errno.EACCES, "Permission denied", "/some/where.csv")

    monkeypatch.setattr("rpbench.commands.scenario._run", handler)
    code, _, err = run_cli(capsys, "scenario", "toy")
    assert_one_error(code, err, "'/some/where.csv': permission denied")


def test_os_error_lines_name_both_paths_of_a_rename():
    exc = OSError(errno.EXDEV, "Invalid cross-device link", "/a", None, "/b")
    assert os_error_line(exc) == "'/a' -> '/b': invalid cross-device link"


# ------------------------------------------------------------ file outputs
@pytest.mark.parametrize(
    "command, option",
    [
        (("report", "RUN"), "--out"),
        (("predict",), "--out"),
        (("oracle", *TOY), "--pairs"),
        (("bench", "--synthetic"), "--csv"),
    ],
)
def test_a_file_output_in_a_missing_folder_fails_first(capsys, tmp_path, toy_run, command, option):
    target = tmp_path / "missing" / "file.csv"
    argv = [str(toy_run) if a == "RUN" else a for a in command]
    code, stdout, err = run_cli(capsys, *argv, option, target)
    assert_one_error(code, err, f"{option} '{target}': folder '{tmp_path / 'missing'}' does not exist")
    assert stdout == ""
    assert_nothing_written(tmp_path, tmp_path / "missing")


@pytest.mark.parametrize("command, option", [(("report", "RUN"), "--out"), (("predict",), "--out")])
def test_a_file_output_that_is_a_folder_fails_first(capsys, tmp_path, toy_run, command, option):
    argv = [str(toy_run) if a == "RUN" else a for a in command]
    code, _, err = run_cli(capsys, *argv, option, tmp_path)
    assert_one_error(code, err, f"{option} '{tmp_path}' is a folder")


def test_a_report_under_proc_fails(capsys, toy_run):
    code, _, err = run_cli(capsys, "report", toy_run, "--out", "/proc/rpbench-report.md")
    assert_one_error(code, err, "--out '/proc/rpbench-report.md': cannot create files in '/proc'")


def test_a_report_in_a_read_only_folder_fails(capsys, tmp_path, toy_run):
    locked = read_only_folder(tmp_path / "locked")
    code, _, err = run_cli(capsys, "report", toy_run, "--out", locked / "report.md")
    assert_one_error(code, err, f"cannot create files in '{locked}'")


def test_a_report_is_written_whole_and_replaces_the_old_one(capsys, tmp_path, toy_run):
    target = tmp_path / "report.md"
    target.write_text("old\n")
    code, stdout, err = run_cli(capsys, "report", toy_run, "--out", target)
    assert code == 0, err
    assert target.read_text().startswith("# rpbench results") and leftovers(tmp_path) == []


def test_a_failed_file_write_leaves_neither_the_file_nor_its_staging(capsys, tmp_path, toy_run, monkeypatch):
    from pathlib import Path

    real_write_text = Path.write_text

    def full_disk(self, *args, **kwargs):  # the disk fills up halfway through the --out file only
        if self.parent != tmp_path:
            return real_write_text(self, *args, **kwargs)
        real_write_text(self, "# rpbench res")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full_disk)
    target = tmp_path / "report.md"
    code, _, err = run_cli(capsys, "report", toy_run, "--out", target)
    assert_one_error(code, err, f"--out '{target}': cannot write the file (No space left on device)")
    assert_nothing_written(tmp_path, target)


# ------------------------------------------------------------ publish
def test_publish_to_a_dangling_link_fails_before_checking(capsys, tmp_path, toy_run):
    dest = tmp_path / "published"
    dest.symlink_to(tmp_path / "nowhere")
    code, stdout, err = run_cli(capsys, "publish", toy_run, dest)
    assert_one_error(code, err, "already exists (a dangling symbolic link)", "choose another DEST")
    assert stdout == "" and dest.is_symlink() and leftovers(tmp_path) == []


def test_publish_under_a_file_fails(capsys, tmp_path, toy_run, a_file):
    code, _, err = run_cli(capsys, "publish", toy_run, a_file / "published")
    assert_one_error(code, err, f"'{a_file}' is not a folder")


def test_publish_over_an_existing_folder_fails(capsys, tmp_path, toy_run):
    code, _, err = run_cli(capsys, "publish", toy_run, toy_run)
    assert_one_error(code, err, "already exists")


def test_a_copy_failing_midway_leaves_no_staging_folder(capsys, tmp_path, toy_run, monkeypatch):
    import shutil

    real_copytree = shutil.copytree

    def copy_then_fail(src, dst, *args, **kwargs):
        real_copytree(src, dst, *args, **kwargs)
        raise OSError(errno.ENOSPC, "No space left on device", str(dst))

    monkeypatch.setattr("rpbench.harness.publish.shutil.copytree", copy_then_fail)
    dest = tmp_path / "published"
    code, _, err = run_cli(capsys, "publish", toy_run, dest)
    assert_one_error(code, err, f"cannot publish to '{dest}'", "No space left on device")
    assert_nothing_written(tmp_path, dest)
