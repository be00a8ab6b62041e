"""Several days of a dated scenario (in parallel workers) and the parallel runner itself."""

from __future__ import annotations

import pandas as pd
import pytest

from rpbench.exceptions import ParameterError
from rpbench.harness.multiday import run_days
from rpbench.harness.parallel import run_tasks
from rpbench.scenarios import ScenarioRequest


def square(x: int) -> int:
    return x * x


@pytest.mark.slow
def test_run_tasks_serial_and_on_a_local_dask_cluster():
    assert run_tasks(square, [1, 2, 3], workers=1) == [1, 4, 9]
    assert run_tasks(square, [3, 1, 2, 5], workers=2, progress=False) == [9, 1, 4, 25]
    with pytest.raises(ParameterError, match="--workers 0"):
        run_tasks(square, [1], workers=0)


@pytest.mark.slow
def test_multi_day_folder(two_day_data, tmp_path):
    data = two_day_data
    request = ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(data))
    folder = run_days(request, ["2017-05-01", "2017-05-02"], strategies=["mb", "rtv"], preset="highs",
                      run_options={}, out=str(tmp_path / "days"), workers=1, scheduler=None, command="test")
    by_day = pd.read_csv(folder / "by_day.csv")
    assert set(by_day["date"]) == {"2017-05-01", "2017-05-02"} and set(by_day["run"]) == {"mb", "rtv"}
    summary = pd.read_csv(folder / "summary.csv")
    assert (summary["count"] == 2).all()
    report = (folder / "report.md").read_text()
    assert "Mean over days" in report and "2 peak hours" in report and (folder / "by_day_total_saving_km.png").is_file()
    from rpbench.results.check import check_folder
    assert all(rc.ok for d in ("2017-05-01", "2017-05-02") for rc in check_folder(folder / d))


@pytest.mark.slow
def test_dates_of_the_synthetic_full_day(fake_data, tmp_path):
    """--dates works for every dated scenario: haikou-day takes its dates from the hourly counts."""
    request = ScenarioRequest("haikou-day", sample=0.1, data_dir=str(fake_data))
    dates = request.dates("2017-05-01..2017-05-31")
    assert dates and all(d.startswith("2017-05") for d in dates)
    folder = run_days(request, dates[:1], strategies=["mb"], preset="highs", run_options={},
                      out=str(tmp_path / "days"), workers=1, scheduler=None, command="test")
    meta = __import__("json").loads((folder / dates[0] / "meta.json").read_text())
    assert meta["scenario"]["name"] == "haikou-day" and meta["scenario"]["args"]["date"] == dates[0]
    assert "scenario `haikou-day`" in (folder / "report.md").read_text()
