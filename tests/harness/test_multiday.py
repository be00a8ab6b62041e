"""Several days of a dated scenario, serially and in worker processes."""

from __future__ import annotations

import pandas as pd
import pytest

from rpbench.harness.multiday import run_days
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_multi_day_folder(two_day_data, tmp_path, workers):
    """In-process and in two spawned workers (the day tasks must pickle): the same folder."""
    data = two_day_data
    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(data))
    spec = RunSpec.of(request, ["mb", "rtv"], command="test")
    folder = run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path / "days"), workers=workers).folder
    by_day = pd.read_csv(folder / "by_day.csv")
    assert set(by_day["date"]) == {"2017-05-01", "2017-05-02"} and set(by_day["run"]) == {"mb", "rtv"}
    summary = pd.read_csv(folder / "summary.csv")
    assert (summary["count"] == 2).all()
    report = (folder / "report.md").read_text()
    assert "Mean over days" in report and "2 peak hours" in report and (folder / "by_day_total_saving_km.png").is_file()
    means = pd.read_csv(folder / "table.csv", index_col="kpi")  # the mean table for a paper, raw and in LaTeX
    mb = summary.set_index(["run", "kpi"])["mean"]
    assert means.loc["total_saving_km", "mb"] == pytest.approx(mb[("mb", "total_saving_km")])
    assert "\\toprule" in (folder / "table.tex").read_text()
    page = (folder / "report.html").read_text()  # the parent's page links each day's page, which exists
    assert all(f'href="{d}/report.html"' in page and (folder / d / "report.html").is_file() for d in by_day["date"])
    assert "Mean over days" in page and "fig-by-day" in page and "by_day_total_saving_km.png" not in page
    from rpbench.check import check_folder

    assert all(rc.ok for d in ("2017-05-01", "2017-05-02") for rc in check_folder(folder / d))


@pytest.mark.slow
def test_dates_of_the_synthetic_full_day(fake_data, tmp_path):
    """--dates works for every dated scenario: haikou-day takes its dates from the hourly counts."""
    request = ScenarioRequest("haikou-day", sample=0.1, data_dir=str(fake_data))
    dates = request.dates("2017-05-01..2017-05-31")
    assert dates and all(d.startswith("2017-05") for d in dates)
    folder = run_days(RunSpec.of(request, ["mb"], command="test"), dates[:1], str(tmp_path / "days"), workers=1).folder
    meta = __import__("json").loads((folder / dates[0] / "meta.json").read_text())
    assert meta["scenario"]["name"] == "haikou-day" and meta["scenario"]["args"]["date"] == dates[0]
    assert "scenario `haikou-day`" in (folder / "report.md").read_text()


def test_a_published_parent_page_is_titled_with_its_name(two_day_data, tmp_path):
    """The parent's page is written while the copy has a temporary name: its title names the published one."""
    from rpbench.harness.publish import publish

    request = ScenarioRequest("haikou-peak", sample=0.3, data_dir=str(two_day_data))
    folder = run_days(
        RunSpec.of(request, ["mb"], command="test"), ["2017-05-01"], str(tmp_path / "days"), workers=1
    ).folder
    out = publish(folder, tmp_path / "published-days")
    assert "<title>rpbench multi-day results: published-days</title>" in (out / "report.html").read_text()


def test_every_day_is_flagged_against_the_decision_budget(two_day_data, tmp_path, capsys):
    """``rpbench run --dates --decision-budget``: each day's folder records the budget and counts against it,
    one note per day and run on stderr, and the tree checks clean."""
    from rpbench.check import check_tree
    from rpbench.cli import main
    from rpbench.results.store import read_meta

    out = tmp_path / "days"
    argv = ["run", "--scenario", "haikou-peak", "--data", str(two_day_data), "--strategies", "mb", "--workers", "1"]
    argv += ["--dates", "2017-05-01..2017-05-02", "--decision-budget", "1e-9", "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    for day in ("2017-05-01", "2017-05-02"):
        assert read_meta(out / day)["decision_budget_s"] == 1e-9
        assert f"rpbench: note: {day}: mb: " in err
    assert read_meta(out)["decision_budget_s"] == 1e-9
    summary = pd.read_csv(out / "summary.csv").set_index(["run", "kpi"])
    assert summary.loc[("mb", "rounds_over_budget"), "count"] == 2
    assert all(found.status == "ok" for found in check_tree(out))


def test_the_per_day_figures_drawn_in_two_processes_give_the_same_report(two_day_data, tmp_path):
    """With a spare core the parent's per-day figures are split with a forked child: the same report.md and
    the same figures as drawn in one process."""
    import shutil

    from rpbench.harness.multiday import write_multiday_report

    request = ScenarioRequest("haikou-peak", sample=0.3, data_dir=str(two_day_data))
    spec = RunSpec.of(request, ["mb", "rtv"], command="test")
    folder = run_days(spec, ["2017-05-01", "2017-05-02"], str(tmp_path / "days"), workers=1).folder
    reports = {}
    for fork in (False, True):
        copy = tmp_path / f"fork-{fork}"
        shutil.copytree(folder, copy)
        for png in copy.glob("by_day_*.png"):
            png.unlink()
        write_multiday_report(copy, name="days", fork=fork)
        reports[fork] = ((copy / "report.md").read_text(), sorted(p.name for p in copy.glob("by_day_*.png")))
    assert reports[True] == reports[False]
    assert len(reports[True][1]) >= 8 and all(f"]({name})" in reports[True][0] for name in reports[True][1])
