"""Tables an older rpbench wrote read under today's KPI names, in one place."""

from __future__ import annotations

import pandas as pd

from rpbench.results.legacy import current_names


def test_older_names_read_as_todays():
    old = pd.DataFrame(
        {
            "run": ["fl", "bound", "bound", "oracle1"],
            "kpi": ["competitive_ratio", "pairing_ratio", "total_saving_km", "pairing_ratio"],
            "value": [1.1, 0.9, 100.0, 0.5],
        }
    )
    new = current_names(old)
    assert new["kpi"].tolist() == ["saving_over_oracle1", "matching_pairing_ratio", "total_saving_km", "pairing_ratio"]
    assert new["value"].tolist() == old["value"].tolist()


def test_a_table_of_today_is_left_as_it_is():
    """Today's parent tables hold the bound's empty cells of rows other runs fill beside its matching_* rows."""
    today = pd.DataFrame(
        {"run": ["bound", "bound"], "kpi": ["pairing_ratio", "matching_pairing_ratio"], "value": [None, 0.9]}
    )
    assert current_names(today)["kpi"].tolist() == ["pairing_ratio", "matching_pairing_ratio"]
    assert current_names(pd.DataFrame({"x": [1]})).equals(pd.DataFrame({"x": [1]}))  # no KPI column
