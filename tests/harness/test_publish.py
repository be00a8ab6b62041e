"""rpbench publish: a light copy only of a folder that passes the checker, never overwriting."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time

import pandas as pd
import pytest
from faults.test_runs_helpers import assert_one_error, error_lines

from rpbench.check import check_tree
from rpbench.cli import main
from rpbench.exceptions import ResultsError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.publish import _only_publish_to, publish
from rpbench.harness.render import render
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=5), ["mb", "oracle1"])
    folder = run_comparison(spec, tmp_path_factory.mktemp("runs") / "toy", progress=False).folder
    return folder


def test_light_copy_keeps_tables_and_the_verdict(run_folder, tmp_path):
    dest = publish(run_folder, tmp_path / "pub")
    assert not (dest / "runs").exists() and not (dest / "orders.csv.gz").exists()
    assert (dest / "kpis.csv").is_file() and "mb: OK" in (dest / "check.txt").read_text()
    md, _ = render([dest])
    assert "light copy" in md
    with pytest.raises(ResultsError, match="already exists"):
        publish(run_folder, dest)


def test_a_folder_failing_the_checker_is_not_published(run_folder, tmp_path, capsys):
    bad = tmp_path / "bad"
    shutil.copytree(run_folder, bad)
    events = bad / "runs" / "mb" / "events.csv.gz"
    pd.read_csv(events).query("event != 'dropoff'").to_csv(events, index=False)
    assert main(["publish", str(bad), str(tmp_path / "pub")]) == 2
    # mb, and the folder's record of its best known schedule (mb's saving, which the event log no longer gives)
    assert "fails rpbench check ((folder), mb)" in capsys.readouterr().err and not (tmp_path / "pub").exists()


@pytest.mark.slow
def test_a_published_multi_day_report_names_the_published_folder(two_day_data, tmp_path):
    from rpbench.harness.multiday import run_days

    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(two_day_data))
    spec = RunSpec.of(request, ["mb"], command="test")
    folder = run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path / "days"), workers=1).folder
    dest = publish(folder, tmp_path / "published-days")
    report = (dest / "report.md").read_text()
    assert "rpbench check PATH/<date>" in report and "`published-days`" in report and "partial" not in report


def test_a_published_parent_keeps_one_page_and_its_days_reports(two_day_data, tmp_path):
    """A day keeps its tables, report and verdict but no page: the parent's page links the day's report."""
    from rpbench.harness.multiday import run_days

    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(two_day_data))
    spec = RunSpec.of(request, ["mb"], command="test")
    folder = run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path / "days"), workers=1).folder
    dest = publish(folder, tmp_path / "published-days")
    for day in ("2017-05-01", "2017-05-02"):
        assert (dest / day / "report.md").is_file() and (dest / day / "check.txt").is_file()
        assert not (dest / day / "report.html").exists()
        assert f'href="{day}/report.md"' in (dest / "report.html").read_text()


def test_a_page_over_the_budget_is_published_without_its_map(run_folder, tmp_path, monkeypatch):
    from rpbench.harness import publish as publishing

    full = publish(run_folder, tmp_path / "with-map")
    monkeypatch.setattr(publishing, "PAGE_BUDGET_BYTES", 1000)
    light = publish(run_folder, tmp_path / "without-map")
    assert "No map" not in (full / "report.html").read_text()
    assert not (light / "report.html").exists()  # without its map still over the budget: no page
    size = (full / "report.html").stat().st_size
    monkeypatch.setattr(publishing, "PAGE_BUDGET_BYTES", size - 1)
    mapless = publish(run_folder, tmp_path / "mapless")
    assert "No map" in (mapless / "report.html").read_text()


def test_the_published_command_names_the_published_folder():
    """A reader reruns the recorded command: ``--out`` names the published folder, no machine path remains."""
    from rpbench.harness.publish import published_command

    ran = "rpbench run --dates 2017-05-01..2017-05-14 --out /scratch/x/peak-hours --data /mnt/d --workers 2"
    assert published_command(ran, "peak-hours") == (
        "rpbench run --dates 2017-05-01..2017-05-14 --out peak-hours --workers 2"
    )
    assert published_command("rpbench run --out=/a/b --data=/c", "b") == "rpbench run --out b"
    assert published_command("rpbench run", "b") == "rpbench run"  # nothing to replace


def test_a_published_folder_records_the_rewritten_command(run_folder, tmp_path):
    import json

    meta = json.loads((run_folder / "meta.json").read_text())
    assert meta["command"] is None or "--out" not in (meta["command"] or "")
    source = tmp_path / "src"
    shutil.copytree(run_folder, source)
    meta["command"] = f"rpbench run --scenario toy --out {source}"
    (source / "meta.json").write_text(json.dumps(meta))
    dest = publish(source, tmp_path / "toy-published")
    published = json.loads((dest / "meta.json").read_text())
    assert published["command"] == "rpbench run --scenario toy --out toy-published"
    assert str(tmp_path) not in (dest / "report.md").read_text()
    assert str(tmp_path) not in (dest / "report.html").read_text()  # the page too, drawn from the snapshot


# ---------------------------------------------------------------- links, snapshots, concurrent publishes
def leftovers_beside(dest) -> list[str]:
    """Staging folders and lock files a publish to ``dest`` may leave beside it."""
    return sorted(p.name for p in dest.parent.iterdir() if p.name.startswith(f".{dest.name}."))


def refuse_to_check(*args, **kwargs):
    raise AssertionError("the checker ran: the link was not refused first")


@pytest.mark.parametrize("what", ["file", "folder"])
def test_a_link_out_of_the_folder_is_refused_before_the_checker(run_folder, tmp_path, capsys, monkeypatch, what):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text("not for publishing\n")
    source = tmp_path / "src"
    shutil.copytree(run_folder, source)
    link = source / "notes.txt" if what == "file" else source / "runs" / "extra"
    link.symlink_to(outside / "secret.txt" if what == "file" else outside)
    monkeypatch.setattr("rpbench.harness.publish.check_tree", refuse_to_check)
    dest = tmp_path / "pub"
    code = main(["publish", str(source), str(dest)])
    line = assert_one_error(code, capsys.readouterr().err, repr(str(link)), "outside the results folder")
    assert str(outside) in line
    assert not dest.exists() and leftovers_beside(dest) == []


def test_a_link_inside_the_folder_is_refused_too(run_folder, tmp_path, capsys):
    """Publishing copies files, not links (rpbench writes none): a link within the folder is refused by name."""
    source = tmp_path / "src"
    shutil.copytree(run_folder, source)
    (source / "kpis-again.csv").symlink_to("kpis.csv")
    dest = tmp_path / "pub"
    code = main(["publish", str(source), str(dest)])
    assert_one_error(code, capsys.readouterr().err, "kpis-again.csv' is a symbolic link (to 'kpis.csv')")
    assert not dest.exists() and leftovers_beside(dest) == []


def test_what_is_published_is_the_checked_snapshot(run_folder, tmp_path, monkeypatch):
    """The source changing right after the checker passed does not reach the published copy."""
    source = tmp_path / "src"
    shutil.copytree(run_folder, source)
    checked = (source / "kpis.csv").read_text()

    def check_then_tamper(path):
        results = check_tree(path)
        (source / "kpis.csv").write_text(checked.replace(",mb,", ",mb-tampered,", 1) + "mb,total_saving_km,1e9\n")
        return results

    monkeypatch.setattr("rpbench.harness.publish.check_tree", check_then_tamper)
    dest = publish(source, tmp_path / "pub")
    assert (dest / "kpis.csv").read_text() == checked
    assert (source / "kpis.csv").read_text() != checked
    assert leftovers_beside(dest) == []


def test_a_publish_to_a_dest_being_published_fails_at_once(run_folder, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("rpbench.harness.publish.check_tree", refuse_to_check)
    dest = tmp_path / "pub"
    with _only_publish_to(dest):  # as another process publishing to DEST holds it
        code = main(["publish", str(run_folder), str(dest)])
    assert_one_error(code, capsys.readouterr().err, f"another publish to {str(dest)!r} is running")
    assert not dest.exists() and leftovers_beside(dest) == []


def test_a_lock_file_left_by_a_killed_publish_does_not_block(run_folder, tmp_path):
    dest = tmp_path / "pub"
    (tmp_path / ".pub.publish.lock").write_text("")  # SIGKILL leaves the file, the kernel drops the lock
    publish(run_folder, dest)
    assert (dest / "check.txt").is_file() and leftovers_beside(dest) == []


def test_a_dest_appearing_while_publishing_is_kept_and_nothing_is_written(run_folder, tmp_path, capsys, monkeypatch):
    dest = tmp_path / "pub"

    def check_while_someone_writes_dest(path):
        dest.mkdir()  # an empty folder: os.rename alone would silently replace it
        return check_tree(path)

    monkeypatch.setattr("rpbench.harness.publish.check_tree", check_while_someone_writes_dest)
    code = main(["publish", str(run_folder), str(dest)])
    assert_one_error(code, capsys.readouterr().err, "already exists")
    assert list(dest.iterdir()) == [] and leftovers_beside(dest) == []


def test_a_failed_publish_removes_its_staging_and_the_folders_it_made(run_folder, tmp_path, capsys, monkeypatch):
    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device", "report.md")

    monkeypatch.setattr("rpbench.harness.publish.write_report", full_disk)
    dest = tmp_path / "new" / "deeper" / "pub"
    assert main(["publish", str(run_folder), str(dest)]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


def test_dest_inside_the_source_is_refused(run_folder, tmp_path, capsys):
    source = tmp_path / "src"
    shutil.copytree(run_folder, source)
    code = main(["publish", str(source), str(source / "pub")])
    assert_one_error(code, capsys.readouterr().err, "is inside the results folder")
    assert not (source / "pub").exists() and leftovers_beside(source / "pub") == []


@pytest.fixture(scope="module")
def other_folder(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=6), ["np"])
    folder = run_comparison(spec, tmp_path_factory.mktemp("runs") / "toy-np", progress=False).folder
    return folder


#: A publish in a child process that starts when the file ``go`` appears (its argv: source, dest, go).
PUBLISH_ON_GO = """
import sys, time
from pathlib import Path
from rpbench.cli import main
source, dest, go = sys.argv[1:]
Path(go + "." + Path(source).name).touch()  # ready
while not Path(go).exists():
    time.sleep(0.005)
sys.exit(main(["publish", source, dest]))
"""


@pytest.mark.slow
def test_two_publishes_to_one_dest_at_once_publish_one_whole_folder(run_folder, other_folder, tmp_path):
    dest, go = tmp_path / "pub", tmp_path / "go"
    children = {
        source: subprocess.Popen(
            [sys.executable, "-c", PUBLISH_ON_GO, str(source), str(dest), str(go)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for source in (run_folder, other_folder)
    }
    deadline = time.monotonic() + 120
    while not all((tmp_path / f"go.{s.name}").exists() for s in children) and time.monotonic() < deadline:
        time.sleep(0.01)
    go.touch()  # both start together
    outcomes = {source: (child.wait(timeout=300), child.communicate()[1]) for source, child in children.items()}
    winners = [source for source, (code, _) in outcomes.items() if code == 0]
    assert len(winners) == 1, outcomes
    [(loser_code, loser_err)] = [outcome for source, outcome in outcomes.items() if source not in winners]
    assert loser_code == 2 and "Traceback" not in loser_err, loser_err
    [line] = error_lines(loser_err)
    assert "another publish to" in line or "already exists" in line, line
    reference = publish(winners[0], tmp_path / "reference")
    assert sorted(p.name for p in dest.rglob("*")) == sorted(p.name for p in reference.rglob("*"))
    for name in ("kpis.csv", "hourly.csv", "check.txt", "table.csv"):
        assert (dest / name).read_text() == (reference / name).read_text(), name
    assert leftovers_beside(dest) == []
