"""A multi-day or sweep parent folder: valid ones pass; a deleted day or point fails ``manifest``, an edited
summary table ``parent-tables``, an edited day that day's own check."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from check.tamper import (
    assert_fails,
    assert_passes,
    cli,
    copy,
    edit_csv,
    edit_meta,
    violations,
    write_fake_haikou,
)
from rpbench.harness.multiday import run_days
from rpbench.harness.sweep import SweepSpec, expand, run_sweep
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """A sweep of Δt over 10 and 30 s (mb, rtv) on the toy city."""
    spec = SweepSpec("check-test", "dt", (10.0, 30.0), ("mb", "rtv"), ("total_saving_km", "response_rate"))
    runs = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=1), ["mb", "rtv"], command="test")
    return run_sweep(
        spec, expand("dt", spec.values), runs, str(tmp_path_factory.mktemp("sweep") / "dt"), workers=1
    ).folder


@pytest.fixture(scope="module")
def multiday(tmp_path_factory):
    """Two peak-hour days of the fake Haikou data folder (mb, oracle1)."""
    data = write_fake_haikou(tmp_path_factory.mktemp("data") / "haikou")
    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(data))
    spec = RunSpec.of(request, ["mb", "oracle1"], oracle_preset="matching", command="test")
    return run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path_factory.mktemp("days") / "days"), workers=1).folder


def test_a_sweep_folder_passes(sweep, capsys):
    """A sweep passes: its points are checked, and sweep.csv holds every point's runs' KPIs."""
    results = assert_passes(sweep, capsys)
    assert len(results) == 3 and results[0].folder_check.checked["children"] == 2
    # points x runs x KPIs (4 of decision time, the ratio against the best known schedule)
    assert results[0].folder_check.checked["sweep"] == 2 * 2 * 24


def test_a_multi_day_folder_passes(multiday, capsys):
    """A multi-day folder passes: its own checks, then every day."""
    results = assert_passes(multiday, capsys)
    assert len(results) == 3 and results[0].folder_check.checked["children"] == 2


def test_a_multi_day_folder_with_a_deleted_day_fails(multiday, tmp_path):
    """A listed day folder deleted fails ``manifest``, and by_day.csv no longer matches the days."""
    folder = copy(multiday, tmp_path)
    shutil.rmtree(folder / "2017-05-02")
    found = assert_fails(folder, "manifest", "day folder 2017-05-02/ listed in meta.json is missing (deleted?)")
    assert any("by_day.csv: rows" in m for m in found["parent-tables"])


def test_a_sweep_with_a_deleted_point_fails(sweep, tmp_path):
    """A listed sweep point folder deleted fails ``manifest``."""
    folder = copy(sweep, tmp_path)
    shutil.rmtree(folder / "dt=30")
    assert_fails(folder, "manifest", "sweep point folder dt=30/ listed in meta.json is missing")


def test_an_old_multi_day_folder_is_held_to_its_dates(multiday, tmp_path):
    """A multi-day folder whose meta.json lists no ``children`` (an older one) is held to its ``dates``."""
    folder = copy(multiday, tmp_path)
    edit_meta(folder, lambda m: m.pop("children"))
    assert_passes(folder)
    shutil.rmtree(folder / "2017-05-01")
    assert_fails(folder, "manifest", "day folder 2017-05-01/ listed in meta.json is missing")


def test_an_edited_per_day_table_fails(multiday, tmp_path):
    """by_day.csv holds the days' kpis.csv: an edited value fails ``parent-tables``."""
    folder = copy(multiday, tmp_path)
    edit_csv(
        folder / "by_day.csv",
        lambda t: t.assign(
            value=np.where((t["run"] == "mb") & (t["kpi"] == "served") & (t["date"] == "2017-05-01"), 0.0, t["value"])
        ),
    )
    assert_fails(folder, "parent-tables", "by_day.csv: value of ('2017-05-01', 'mb', 'served') is 0.0")


def test_an_edited_mean_over_days_fails(multiday, tmp_path):
    """summary.csv holds the statistics over the days: an edited mean fails ``parent-tables``."""
    folder = copy(multiday, tmp_path)
    edit_csv(
        folder / "summary.csv",
        lambda t: t.assign(
            mean=np.where((t["run"] == "mb") & (t["kpi"] == "total_saving_km"), t["mean"] + 1.0, t["mean"])
        ),
    )
    assert_fails(folder, "parent-tables", "summary.csv: mean of ('mb', 'total_saving_km')")


def test_an_edited_sweep_table_fails(sweep, tmp_path):
    """sweep.csv holds the points' kpis.csv: an edited value fails ``parent-tables``."""
    folder = copy(sweep, tmp_path)
    edit_csv(
        folder / "sweep.csv",
        lambda t: t.assign(
            value=np.where((t["run"] == "rtv") & (t["kpi"] == "pairs") & (t["label"] == "dt=10"), 1.0, t["value"])
        ),
    )
    assert_fails(folder, "parent-tables", "sweep.csv: value of ('dt=10', 'rtv', 'pairs') is 1.0")


def test_a_day_edited_inside_a_multi_day_folder_fails_that_day(multiday, tmp_path, capsys):
    """A day's own files are checked as a comparison folder: an edited event log fails that day."""
    folder = copy(multiday, tmp_path)
    edit_csv(folder / "2017-05-02" / "runs" / "mb" / "events.csv.gz", lambda ev: ev[ev["event"] != "dropoff"])
    found = violations(folder)
    assert "service" in found
    code, out, _ = cli(["check", str(folder)], capsys)
    assert code == 1 and f"== {folder / '2017-05-02'}" in out
