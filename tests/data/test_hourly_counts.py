"""Hourly order counts (the diurnal profile of haikou-day)."""

from __future__ import annotations

import pytest

from rpbench.data import hourly_counts_for, read_hourly_counts
from rpbench.exceptions import DataError, DataNotFoundError


def test_real_counts(data_dir):
    table = read_hourly_counts(data_dir)
    assert len(table) == 184
    may1 = hourly_counts_for(data_dir, "2017-05-01")
    assert may1.sum() == 52124 and may1[8] == 1641


def test_missing_date(fake_data):
    with pytest.raises(DataNotFoundError, match="no hourly counts for 2017-07-04"):
        hourly_counts_for(fake_data, "2017-07-04")


def test_counts_must_add_up(fake_data):
    path = fake_data / "samples_and_aggregates" / "data_dayly_hourly_count.csv"
    path.write_text('date,day_count,hour_count\n05/01,999,"[1, 2]"\n')
    with pytest.raises(DataError, match="24 non-negative integers"):
        read_hourly_counts(fake_data)
