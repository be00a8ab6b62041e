"""rpbench publish: a light copy only of a folder that passes the checker, never overwriting."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

from rpbench.cli import main
from rpbench.exceptions import ResultsError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.publish import publish
from rpbench.harness.render import render
from rpbench.harness.spec import RunSpec
from rpbench.scenarios import ScenarioRequest


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=5), ["mb", "oracle1"])
    folder, _ = run_comparison(spec, tmp_path_factory.mktemp("runs") / "toy", progress=False)
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
    assert "fails rpbench check (mb)" in capsys.readouterr().err and not (tmp_path / "pub").exists()


@pytest.mark.slow
def test_a_published_multi_day_report_names_the_published_folder(two_day_data, tmp_path):
    from rpbench.harness.multiday import run_days

    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(two_day_data))
    spec = RunSpec.of(request, ["mb"], command="test")
    folder = run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path / "days"), workers=1)
    dest = publish(folder, tmp_path / "published-days")
    report = (dest / "report.md").read_text()
    assert "rpbench check PATH/<date>" in report and "`published-days`" in report and "partial" not in report


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
