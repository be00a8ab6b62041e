"""A published parent records what its light children keep, so ``rpbench check`` of the copy recomputes the
parent's tables from children it proves unedited (an evaluation's case: tests/faults/test_evaluation_record.py)."""

from __future__ import annotations

import json

import pandas as pd
from check.tamper import assert_fails, assert_passes, edit_meta

from rpbench.cli import main
from rpbench.harness.multiday import run_days, write_summary
from rpbench.harness.publish import publish
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

DAYS = ["2017-05-01", "2017-05-02"]


def published_days(data, tmp_path):
    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(data))
    folder = run_days(RunSpec.of(request, ["mb"], command="test"), DAYS, str(tmp_path / "days"), workers=1).folder
    return publish(folder, tmp_path / "published-days")


def test_a_published_multi_day_folder_is_checked_against_its_days_digests(two_day_data, tmp_path, capsys):
    dest = published_days(two_day_data, tmp_path)
    record = json.loads((dest / "meta.json").read_text())["light_copy"]
    assert sorted(record["children"]) == DAYS
    (parent, *days) = assert_passes(dest, capsys)
    assert [d.folder_check.checked["published_files"] for d in days] == [3, 3]

    kpis = dest / DAYS[1] / "kpis.csv"  # a day's KPI edited, the parent's tables recomputed from it
    table = pd.read_csv(kpis)
    table.loc[(table["run"] == "mb") & (table["kpi"] == "served"), "value"] += 1
    table.to_csv(kpis, index=False)
    write_summary(dest)
    assert_fails(dest, "light-copy", "kpis.csv is not the file published")
    assert main(["check", str(dest)]) == 1


def test_a_copy_published_before_the_record_is_checked_without_it(two_day_data, tmp_path, capsys):
    dest = published_days(two_day_data, tmp_path)
    edit_meta(dest, lambda m: m.pop("light_copy"))
    (parent, *days) = assert_passes(dest, capsys)
    assert all("published before rpbench recorded" in d.folder_check.skipped["light-copy"] for d in days)
