"""The compiled prediction reproduces the numpy implementation's fixed point (rpbench at commit 677b415).

``golden/`` holds P_w, ē(p) and ē(s) per OD computed by that implementation
for the 2017-05-01 peak orders (``rpbench predict --rates day``: all 1,867
ODs) and, for the 21-day month table, its sums and λ-weighted means and every
97th OD.  The fixed point must agree to 1e-9 (probabilities absolutely,
distances relatively).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rpbench.predict import PredictConfig, predict
from rpbench.predict.rates import load_rates
from rpbench.scenarios.base import Params
from rpbench.scenarios.common import haikou_network

GOLDEN = Path(__file__).parent / "golden"
COLUMNS = ("matching_prob", "e_vacant", "e_seeker")


def table(data_dir: Path, kind: str) -> pd.DataFrame:
    net = haikou_network(data_dir)
    rates = load_rates(kind, net, data_dir, "2017-05-01" if kind == "day" else None)
    return predict(net, rates, Params(), PredictConfig(), use_cache=False).per_od_table()


def assert_close(got: pd.DataFrame, want: pd.DataFrame) -> None:
    merged = want.merge(got, on=["origin_id", "destination_id"], suffixes=("_want", ""), validate="1:1")
    assert len(merged) == len(want)
    np.testing.assert_allclose(merged["matching_prob"], merged["matching_prob_want"], rtol=0, atol=1e-9)
    for col in ("e_vacant", "e_seeker"):
        np.testing.assert_allclose(merged[col], merged[f"{col}_want"], rtol=1e-9, atol=1e-9)


@pytest.mark.haikou
def test_day_set_matches_the_numpy_implementation(data_dir):
    assert_close(table(data_dir, "day"), pd.read_csv(GOLDEN / "day-2017-05-01.csv.gz"))


@pytest.mark.haikou
@pytest.mark.slow
def test_month_table_matches_the_numpy_implementation(data_dir):
    got = table(data_dir, "month")
    assert_close(got, pd.read_csv(GOLDEN / "month-every-97th.csv"))
    summary = json.loads((GOLDEN / "month-summary.json").read_text())
    assert len(got) == summary["ods"]
    lam = got["rate_per_s"]
    for col in COLUMNS:
        assert got[col].sum() == pytest.approx(summary[f"{col}_sum"], rel=1e-9)
        assert (lam * got[col]).sum() / lam.sum() == pytest.approx(summary[f"{col}_lam_mean"], rel=1e-9)
