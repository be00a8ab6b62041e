"""Every number a reader is shown — kpis.csv, hourly.csv, report.md's tables — edited: each fails by name.

The checker recomputes the KPIs with its own code (not rpbench.results.metrics) from the event log and the
odometers, so an edit of any reported figure is caught, whatever it is.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_fails,
    edit_csv,
    set_kpi,
    violations,
)
from rpbench.results.check import check_tree

base, folder = helpers.base, helpers.folder  # fixtures (clean folders built once per module)


def nudge(value):
    """A visible change of any reported value (an undefined one, reported empty, becomes 1)."""
    return 1.0 if pd.isna(value) else float(value) * 1.01 + 1.0


SIMULATION_KPIS = [
    "orders",
    "served",
    "cancelled",
    "pooled_passengers",
    "pairs",
    "response_rate",
    "pairing_ratio",
    "pairing_ratio_of_orders",
    "platform_profit_cny",
    "platform_profit_alt_cny",
    "avg_response_time_s",
    "avg_pickup_time_s",
    "avg_pickup_distance_m",
    "avg_detour_m",
    "avg_shared_m",
    "total_occupied_km",
    "total_solo_served_km",
    "total_saving_km",
    "competitive_ratio_bound",
]


@pytest.mark.parametrize("kpi", SIMULATION_KPIS)
def test_every_strategy_kpi_edited_fails_by_name(folder, kpi):
    set_kpi(folder, "mb", kpi, nudge)
    assert_fails(folder, "kpi", f"KPI {kpi}: reported", run="mb")


@pytest.mark.parametrize(
    "run, kpi",
    [
        ("oracle1", k)
        for k in (
            "orders",
            "pairs",
            "pooled_passengers",
            "pairing_ratio",
            "avg_detour_m",
            "avg_shared_m",
            "total_saving_km",
            "objective_m",
        )
    ]
    + [("oracle2", "avg_detour_m"), ("bound", "avg_shared_m"), ("bound", "pairs")],
)
def test_every_oracle_kpi_edited_fails_by_name(folder, run, kpi):
    set_kpi(folder, run, kpi, nudge)
    assert_fails(folder, "kpi", f"KPI {kpi}: reported", run=run)


def test_a_raised_solver_bound_with_a_zero_gap_fails(folder):
    set_kpi(folder, "oracle1", "bound_m", lambda v: v + 500.0)
    assert_fails(folder, "kpi", "KPI bound_m: reported", run="oracle1")


def test_a_solver_bound_below_its_own_solution_fails(folder):
    set_kpi(folder, "oracle2", "bound_m", lambda v: v - 500.0)
    assert_fails(folder, "kpi", "lies below its solution", run="oracle2")


def test_oracle2_claiming_fewer_possible_pairs_than_it_found_fails(folder):
    set_kpi(folder, "oracle2", "pairs_bound", lambda v: v - 1)
    assert_fails(folder, "kpi", "KPI pairs_bound: the proven maximum number of pairs", run="oracle2")


def test_oracle1_claiming_a_pair_bound_fails(folder):
    set_kpi(folder, "oracle1", "pairs_bound", lambda v: 5.0)
    assert_fails(folder, "kpi", "for an oracle that proves none", run="oracle1")


def test_a_lowered_upper_bound_fails_its_own_kpi_and_every_certificate(folder):
    set_kpi(folder, "bound", "total_saving_km", lambda v: 0.001)
    found = assert_fails(folder, "kpi", "KPI total_saving_km: reported 0.001", run="bound")
    assert any(m.startswith("mb: saving") and "exceeds the upper bound" in m for m in found["bound-certificate"])


def test_a_text_kpi_value_fails(folder):
    set_kpi(folder, "mb", "avg_detour_m", lambda v: "lots")
    assert_fails(folder, "kpi", "KPI avg_detour_m: reported 'lots' is not a number", run="mb")


def test_an_undefined_kpi_reported_empty_fails(folder):
    set_kpi(folder, "rtv", "total_saving_km", lambda v: np.nan)
    assert_fails(folder, "kpi", "KPI total_saving_km: reported nan", run="rtv")


def test_a_deleted_kpi_row_fails(folder):
    edit_csv(folder / "kpis.csv", lambda t: t[~((t["run"] == "fl") & (t["kpi"] == "served"))])
    assert_fails(folder, "kpi", "KPI served is not reported", run="fl")


def test_a_duplicated_kpi_row_fails(folder):
    edit_csv(folder / "kpis.csv", lambda t: pd.concat([t, t[(t["run"] == "mb") & (t["kpi"] == "pairs")]]))
    assert_fails(folder, "kpi", "KPI pairs is reported twice", run="mb")


def test_an_invented_kpi_fails(folder):
    edit_csv(
        folder / "kpis.csv", lambda t: pd.concat([t, pd.DataFrame([{"run": "mb", "kpi": "happiness", "value": 1.0}])])
    )
    assert_fails(folder, "kpi", "KPI happiness in kpis.csv is not a KPI rpbench reports", run="mb")


def test_kpis_of_a_run_that_is_not_in_the_folder_fail(folder):
    edit_csv(
        folder / "kpis.csv", lambda t: pd.concat([t, pd.DataFrame([{"run": "ghost", "kpi": "orders", "value": 1.0}])])
    )
    assert_fails(folder, "manifest", "kpis.csv reports run(s) 'ghost'")


def test_an_impossible_timing_fails(folder):
    set_kpi(folder, "rtv", "wall_s", lambda v: -3.0)
    assert_fails(folder, "kpi", "KPI wall_s: reported -3.0, not a time or size", run="rtv")


def test_a_strategys_preparation_time_is_an_unverified_timing(folder):
    """prepare_s (a strategy's one-off prepare()) is reported, not recomputed: finite and >= 0 passes."""
    rows = pd.DataFrame(
        [{"run": "mb", "kpi": "prepare_s", "value": 0.25}, {"run": "fl", "kpi": "prepare_s", "value": -1}]
    )
    edit_csv(folder / "kpis.csv", lambda t: pd.concat([t, rows]))
    found = violations(folder)
    assert found == {"kpi": ["fl: KPI prepare_s: reported -1.0, not a time or size (finite, >= 0)"]}


# ----------------------------------------------------------------- hourly.csv
def edit_hourly(folder, run, column, fn, hour=0):
    def edit(t):
        t[column] = t[column].astype(object)
        sel = (t["run"] == run) & (t["hour"] == hour)
        t.loc[sel, column] = fn(t.loc[sel, column].iloc[0])

    edit_csv(folder / "hourly.csv", edit)


@pytest.mark.parametrize(
    "column",
    [
        "orders",
        "response_rate",
        "pairing_ratio",
        "avg_detour_m",
        "avg_shared_m",
        "total_saving_km",
        "avg_pickup_m",
        "avg_pickup_time_s",
    ],
)
def test_every_hourly_figure_edited_fails(folder, column):
    edit_hourly(folder, "fl", column, nudge)
    assert_fails(folder, "hourly", f"hour 0: {column} reported", run="fl")


def test_the_bounds_hourly_saving_edited_fails(folder):
    edit_hourly(folder, "bound", "total_saving_km", nudge)
    assert_fails(folder, "hourly", "hour 0: total_saving_km reported", run="bound")


def test_a_figure_added_to_the_bounds_hourly_row_fails(folder):
    edit_hourly(folder, "bound", "avg_detour_m", lambda v: 123.0)
    assert_fails(folder, "hourly", "avg_detour_m reported 123.0, recomputed nan", run="bound")


def test_an_invented_hour_fails(folder):
    def add(t):
        row = t[t["run"] == "mb"].iloc[[0]].assign(hour=5)
        return pd.concat([t, row])

    edit_csv(folder / "hourly.csv", add)
    assert_fails(folder, "hourly", "hourly.csv has hours", run="mb")


def test_hourly_rows_of_an_oracle_fail(folder):
    edit_csv(folder / "hourly.csv", lambda t: pd.concat([t, t[t["run"] == "mb"].assign(run="oracle1")]))
    assert_fails(folder, "hourly", "hourly.csv has rows of run 'oracle1'")


# ------------------------------------------------------------------ report.md
def test_a_number_edited_in_report_md_alone_fails(folder):
    path = folder / "report.md"
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("| Total distance saving"))
    cells = lines[k].split(" | ")
    cells[1] = "999.9"
    lines[k] = " | ".join(cells)
    path.write_text("\n".join(lines) + "\n")
    assert_fails(folder, "report", "report.md shows Total distance saving due to ride-pooling (km): 999.9 | ")


def test_a_row_deleted_from_report_md_is_reported_as_not_compared(folder):
    path = folder / "report.md"
    path.write_text(
        "\n".join(line for line in path.read_text().splitlines() if not line.startswith("| Pairing ratio")) + "\n"
    )
    assert "report" not in violations(folder)  # nothing false is shown: said, not failed
    (found,) = check_tree(folder)
    assert (
        "report.md rows not compared" in found.folder_check.skipped["report"]
        and "Pairing ratio" in found.folder_check.skipped["report"]
    )
