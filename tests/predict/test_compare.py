"""rpbench vs the authors' published 2017-05-01 predictions (needs the Haikou data)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.data.od_rates import AUTHORS_PREDICTION_COLUMNS as COLUMNS
from rpbench.predict import day_table_rates, predict
from rpbench.predict.compare import compare
from rpbench.scenarios.common import haikou_network


@pytest.mark.slow
def test_compare_with_the_authors(data_dir):
    net = haikou_network(data_dir)
    pred = predict(net, day_table_rates(net, data_dir), use_cache=False)
    summary, frame = compare(pred, data_dir)
    assert summary["ods_joined"] == 1698 == len(frame)
    names = [row["column"] for row in summary["columns"]]
    assert names == list(COLUMNS)
    row = summary["columns"][0]
    assert row["column"] == "matching_prob" and 0 < row["mean_ours"] <= 1 and 0 < row["mean_authors"] <= 1
    # Solo distances agree (same network and OD set) even though the models differ in detail.
    solo = frame["solo_distance"].to_numpy()
    assert np.all(frame["ride_distance_ours"].to_numpy() >= solo - 1e-6)
