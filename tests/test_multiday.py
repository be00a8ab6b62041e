"""Peak hours of several days (in parallel workers) and the parallel runner itself."""

from __future__ import annotations

import pandas as pd
import pytest

from rpbench.exceptions import ParameterError
from rpbench.multiday import parse_dates, run_days
from rpbench.parallel import run_tasks


def square(x: int) -> int:
    return x * x


def test_run_tasks_serial_and_on_a_local_dask_cluster():
    assert run_tasks(square, [1, 2, 3], workers=1) == [1, 4, 9]
    assert run_tasks(square, [3, 1, 2, 5], workers=2, progress=False) == [9, 1, 4, 25]
    with pytest.raises(ParameterError, match="--workers 0"):
        run_tasks(square, [1], workers=0)


def two_days(fake_data):
    """A second day in the same format: the first day's orders moved to 2017-05-02."""
    import gzip
    folder = fake_data / "demand_0800_0900" / "orders"
    with gzip.open(folder / "2017-05-01.csv.gz", "rt") as fh:
        text = fh.read().replace("2017-05-01 08:", "2017-05-02 08:")
    with gzip.open(folder / "2017-05-02.csv.gz", "wt") as fh:
        fh.write(text)
    return fake_data


def test_parse_dates(fake_data):
    data = two_days(fake_data)
    assert parse_dates("2017-04-01..2017-05-31", data) == ["2017-05-01", "2017-05-02"]
    assert parse_dates("2017-05-02", data) == ["2017-05-02"]
    with pytest.raises(ParameterError, match="no peak-hour order file for 2017-05-09"):
        parse_dates("2017-05-01,2017-05-09", data)
    with pytest.raises(ParameterError, match="ends before it starts"):
        parse_dates("2017-05-02..2017-05-01", data)


def test_multi_day_folder(fake_data, tmp_path):
    data = two_days(fake_data)
    folder = run_days(["2017-05-01", "2017-05-02"], data_dir=str(data), sample=1.0, seed=0, param_overrides={},
                      fleet_placement="order_origins", strategies=["mb", "rtv"], preset="highs",
                      strategy_options={}, out=str(tmp_path / "days"), workers=1, scheduler=None, command="test")
    by_day = pd.read_csv(folder / "by_day.csv")
    assert set(by_day["date"]) == {"2017-05-01", "2017-05-02"} and set(by_day["run"]) == {"mb", "rtv"}
    summary = pd.read_csv(folder / "summary.csv")
    assert (summary["count"] == 2).all()
    report = (folder / "report.md").read_text()
    assert "Mean over days" in report and (folder / "by_day_total_saving_km.png").is_file()
    from rpbench.check import check_folder
    assert all(rc.ok for d in ("2017-05-01", "2017-05-02") for rc in check_folder(folder / d))
