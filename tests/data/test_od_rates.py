"""OD rate tables and the authors' published predictions."""

from __future__ import annotations

import gzip

import pytest

from rpbench.data import read_authors_predictions, read_day_od_shares, read_month_od_rates
from rpbench.exceptions import DataError


def test_month_table_is_orders_per_second(data_dir):
    rates = read_month_od_rates(data_dir)
    assert len(rates) == 39510
    # Σλ = 51.83 orders/min = 65,304 orders / 1,260 min (SOURCE.md)
    assert rates["rate_per_s"].sum() * 60 == pytest.approx(65304 / 1260, rel=1e-9)


def test_day_table_shares_and_predictions(data_dir):
    shares = read_day_od_shares(data_dir)
    assert len(shares) == 1698
    assert shares["share"].sum() == pytest.approx(1.0, abs=1e-6)
    pred = read_authors_predictions(data_dir)
    assert len(pred) == 1698 and set(pred["od_id"]) == set(shares["od_id"])


def test_negative_rate_rejected(fake_data):
    path = fake_data / "demand_0800_0900" / "month_5_OD.csv.gz"
    with gzip.open(path, "wt") as fh:
        fh.write("OD_id,origin_id,destination_id,lambda\n0,1,2,-0.5\n")
    with pytest.raises(DataError, match="negative rate"):
        read_month_od_rates(fake_data)
