"""The competitive ratio as an interval [saving / U, saving / LB] and the bracket [LB, U], on hand-made tables."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from rpbench.report.comparison import fmt
from rpbench.results.ratios import best_known, bracket_line, bracket_record, derived_rows, over, with_ratios


def table(**savings: float) -> pd.DataFrame:
    return pd.DataFrame({run: {"total_saving_km": s, "pairing_ratio": 0.5} for run, s in savings.items()})


def test_over_is_undefined_without_a_positive_denominator():
    assert over(3.0, 4.0) == 0.75
    assert all(math.isnan(over(1.0, d)) for d in (0.0, -1.0, float("nan"), None))


def test_the_best_known_schedule_is_the_largest_saving_first_of_equals():
    assert best_known({"mb": 5.0, "fl": 7.0, "rtv": 7.0}).run == "fl"
    assert best_known({"mb": float("nan"), "np": 0.0}).run == "np"  # an undefined saving is no schedule
    assert best_known({}) is None


def test_every_simulated_run_gets_its_interval_and_the_bound_the_bracket():
    rows = derived_rows({"mb": 4.0, "hindsight": 8.0}, {"bound": 10.0, "oracle1": 5.0})
    assert rows["mb"] == {
        "competitive_ratio_bound": 0.4,
        "competitive_ratio_best_known": 0.5,
        "saving_over_oracle1": 0.8,
    }
    assert rows["hindsight"]["competitive_ratio_best_known"] == 1.0
    assert rows["bound"] == {"best_known_saving_km": 8.0, "bound_over_best_known": 1.25}
    assert set(rows) == {"mb", "hindsight", "bound"}  # offline runs get no ratio


def test_an_lb_of_zero_leaves_the_ratio_to_it_undefined():
    rows = derived_rows({"np": 0.0}, {"bound": 10.0})
    assert rows["np"]["competitive_ratio_bound"] == 0.0
    assert math.isnan(rows["np"]["competitive_ratio_best_known"]) and math.isnan(rows["bound"]["bound_over_best_known"])


def test_with_ratios_recomputes_and_never_trusts_stored_rows():
    wide = table(mb=4.0, fl=6.0, bound=12.0)
    wide.loc["competitive_ratio_bound", "mb"] = 0.99  # a stale or edited row
    out = with_ratios(wide, ["mb", "fl"])
    assert out.loc["competitive_ratio_bound", "mb"] == pytest.approx(1 / 3)
    assert out.loc["competitive_ratio_best_known", "mb"] == pytest.approx(2 / 3)
    assert pd.isna(out.loc["competitive_ratio_bound", "bound"])
    assert out.loc["bound_over_best_known", "bound"] == 2.0
    assert "saving_over_oracle1" not in out.index  # no Oracle-1 among the runs


def test_the_line_under_a_table_says_where_opt_lies():
    wide = with_ratios(table(mb=1046.0, hindsight=999.0, bound=1150.0), ["mb", "hindsight"])
    styles = {"mb": ("MB", None)}
    line = bracket_line(wide, ["mb", "hindsight"], fmt, styles)
    assert line == "OPT lies in [LB, U] = [1,046, 1,150] km (U / LB = 1.10; best known schedule: MB)."
    alone = bracket_line(table(mb=50.0), ["mb"], fmt, styles)
    assert alone == "OPT >= LB = 50.0 km (best known schedule: MB; no upper bound run, so no U)."
    assert bracket_line(table(bound=5.0), [], fmt) is None  # no simulated run: no schedule known
    record = bracket_record(wide, ["mb", "hindsight"])
    assert record == {"best_known": {"run": "mb", "saving_km": 1046.0}, "upper_bound_km": 1150.0,
                      "bound_over_best_known": pytest.approx(1150 / 1046)}  # fmt: skip
