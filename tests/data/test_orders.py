"""Order readers: peak-hour files of any date, raw coordinates, the GAIA sample, the trace."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

from rpbench.data import (
    available_peak_dates,
    read_gaia_sample,
    read_peak_orders,
    read_raw_peak_orders,
    read_trace_orders,
)
from rpbench.exceptions import DataError, DataNotFoundError, ParameterError


def test_peak_hour_keeps_departures_inside_the_hour(data_dir):
    frame = read_peak_orders(data_dir, "2017-05-01")
    assert len(frame) == 2018  # 2,035 rows, 17 outside [08:00, 09:00)
    assert frame["departure_time"].min() >= pd.Timestamp("2017-05-01 08:00")
    assert frame["departure_time"].max() < pd.Timestamp("2017-05-01 09:00")
    assert frame["departure_time"].is_monotonic_increasing


def test_available_dates_are_discovered_not_assumed(fake_data):
    assert available_peak_dates(fake_data) == ["2017-05-01"]
    folder = fake_data / "demand_0800_0900" / "orders"
    shutil.copy(folder / "2017-05-01.csv.gz", folder / "2017-06-02.csv.gz")
    assert available_peak_dates(fake_data) == ["2017-05-01", "2017-06-02"]
    # another day in the same format works (its rows carry 05-01 times, so none falls in 06-02's hour)
    assert len(read_peak_orders(fake_data, "2017-06-02")) == 0
    assert len(read_peak_orders(fake_data, "2017-05-01")) == 40


def test_date_without_file_names_the_available_dates(fake_data):
    with pytest.raises(DataNotFoundError, match="no peak-hour order file for 2017-05-09.*available: 2017-05-01"):
        read_peak_orders(fake_data, "2017-05-09")


def test_bad_date_text(fake_data):
    with pytest.raises(ParameterError, match="YYYY-MM-DD"):
        read_peak_orders(fake_data, "May 1st")


def test_bad_departure_time(fake_data, tmp_path):
    import gzip

    path = fake_data / "demand_0800_0900" / "orders" / "2017-05-01.csv.gz"
    with gzip.open(path, "rt") as fh:
        lines = fh.read().splitlines()
    lines[3] = lines[3].replace("2017-05-01 08:", "yesterday 08:")
    with gzip.open(path, "wt") as fh:
        fh.write("\n".join(lines) + "\n")
    with pytest.raises(DataError, match="departure_time', data row 3"):
        read_peak_orders(fake_data, "2017-05-01")


def test_raw_coordinates_and_gaia_sample(data_dir):
    raw = read_raw_peak_orders(data_dir)
    assert len(raw) == 2035
    assert {"origin_lon", "origin_lat", "dest_lon", "dest_lat"} <= set(raw.columns)
    gaia = read_gaia_sample(data_dir)
    assert len(gaia) == 13481


def test_trace(data_dir):
    trace = read_trace_orders(data_dir)
    assert len(trace) == 18367
    assert trace["departure_time"].min() >= pd.Timestamp("2017-07-01")
