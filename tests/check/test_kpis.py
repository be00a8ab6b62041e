"""Every number a reader is shown — kpis.csv, hourly.csv, report.md's tables — edited: each fails by name.

The checker recomputes the KPIs with its own code (not rpbench.results.metrics) from the event log and the
odometers, so an edit of any reported figure is caught, whatever it is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from check.tamper import (
    assert_fails,
    assert_passes,
    cli,
    copy,
    edit_csv,
    edit_meta,
    run_violations,
    set_kpi,
    violations,
)
from rpbench.check import check_tree
from rpbench.harness.comparison import run_comparison
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


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
]


@pytest.mark.parametrize("kpi", SIMULATION_KPIS)
def test_every_strategy_kpi_edited_fails_by_name(folder, kpi):
    """Every KPI of a strategy run is recomputed: any one edited fails ``kpi`` by its name."""
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
    + [("oracle2", "avg_detour_m"), ("bound", "matching_avg_shared_m"), ("bound", "pairs")],
)
def test_every_oracle_kpi_edited_fails_by_name(folder, run, kpi):
    """Every recomputed KPI of an oracle or the bound, edited, fails ``kpi`` by its name."""
    set_kpi(folder, run, kpi, nudge)
    assert_fails(folder, "kpi", f"KPI {kpi}: reported", run=run)


def test_a_raised_solver_bound_with_a_zero_gap_fails(folder):
    """With a gap of 0 the solver's bound is its objective."""
    set_kpi(folder, "oracle1", "bound_m", lambda v: v + 500.0)
    assert_fails(folder, "kpi", "KPI bound_m: reported", run="oracle1")


def test_a_solver_bound_below_its_own_solution_fails(folder):
    """The solver's bound is never below the value of its own solution."""
    set_kpi(folder, "oracle2", "bound_m", lambda v: v - 500.0)
    assert_fails(folder, "kpi", "lies below its solution", run="oracle2")


def test_oracle2_claiming_fewer_possible_pairs_than_it_found_fails(folder):
    """Oracle-2's proven maximum number of pairs covers the pairs it found."""
    set_kpi(folder, "oracle2", "pairs_bound", lambda v: v - 1)
    assert_fails(folder, "kpi", "KPI pairs_bound: the proven maximum number of pairs", run="oracle2")


def test_oracle1_claiming_a_pair_bound_fails(folder):
    """Only Oracle-2 proves a maximum number of pairs; Oracle-1 reporting one fails."""
    set_kpi(folder, "oracle1", "pairs_bound", lambda v: 5.0)
    assert_fails(folder, "kpi", "for an oracle that proves none", run="oracle1")


def test_a_text_kpi_value_fails(folder):
    """A reported KPI that is text fails ``kpi``."""
    set_kpi(folder, "mb", "avg_detour_m", lambda v: "lots")
    assert_fails(folder, "kpi", "KPI avg_detour_m: reported 'lots' is not a number", run="mb")


def test_an_undefined_kpi_reported_empty_fails(folder):
    """A defined KPI reported empty (NaN) fails ``kpi``."""
    set_kpi(folder, "rtv", "total_saving_km", lambda v: np.nan)
    assert_fails(folder, "kpi", "KPI total_saving_km: reported nan", run="rtv")


def test_a_deleted_kpi_row_fails(folder):
    """Every recomputed KPI is reported."""
    edit_csv(folder / "kpis.csv", lambda t: t[~((t["run"] == "fl") & (t["kpi"] == "served"))])
    assert_fails(folder, "kpi", "KPI served is not reported", run="fl")


def test_a_duplicated_kpi_row_fails(folder):
    """No KPI is reported twice."""
    edit_csv(folder / "kpis.csv", lambda t: pd.concat([t, t[(t["run"] == "mb") & (t["kpi"] == "pairs")]]))
    assert_fails(folder, "kpi", "KPI pairs is reported twice", run="mb")


def test_an_invented_kpi_fails(folder):
    """A KPI rpbench does not report for the run's kind fails ``kpi``."""
    edit_csv(
        folder / "kpis.csv", lambda t: pd.concat([t, pd.DataFrame([{"run": "mb", "kpi": "happiness", "value": 1.0}])])
    )
    assert_fails(folder, "kpi", "KPI happiness in kpis.csv is not a KPI rpbench reports", run="mb")


def test_kpis_of_a_run_that_is_not_in_the_folder_fail(folder):
    """kpis.csv reports only runs meta.json lists."""
    edit_csv(
        folder / "kpis.csv", lambda t: pd.concat([t, pd.DataFrame([{"run": "ghost", "kpi": "orders", "value": 1.0}])])
    )
    assert_fails(folder, "manifest", "kpis.csv reports run(s) 'ghost'")


def test_an_impossible_timing_fails(folder):
    """An unverifiable timing is at least finite and >= 0."""
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


def test_reported_kpi_tampering_is_caught(clean_copy):
    """A reported saving edited in kpis.csv fails ``kpi``."""
    kpis = pd.read_csv(clean_copy / "kpis.csv")
    kpis.loc[(kpis["run"] == "mb") & (kpis["kpi"] == "total_saving_km"), "value"] += 1.0
    kpis.to_csv(clean_copy / "kpis.csv", index=False)
    found = run_violations(clean_copy)
    assert any("total_saving_km" in m for m in found["kpi"])


def test_reading_a_kpi_file_of_text_is_not_a_crash(folder, capsys):
    """kpis.csv is what is checked, not an input: a text value is a failed ``kpi`` check (exit 1)."""
    edit_csv(folder / "kpis.csv", lambda t: t.assign(value=t["value"].astype(object).where(t["run"] != "rtv", "x")))
    code, out, err = cli(["check", str(folder)], capsys)
    assert code == 1 and "rtv: FAILED" in out and "is not a number" in out and err == ""


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
    """Every figure of hourly.csv is recomputed per request hour: any one edited fails ``hourly``."""
    edit_hourly(folder, "fl", column, nudge)
    assert_fails(folder, "hourly", f"hour 0: {column} reported", run="fl")


def test_the_bounds_hourly_saving_edited_fails(folder):
    """The bound's hourly saving is its matching's, per hour of the earlier request."""
    edit_hourly(folder, "bound", "total_saving_km", nudge)
    assert_fails(folder, "hourly", "hour 0: total_saving_km reported", run="bound")


def test_a_figure_added_to_the_bounds_hourly_row_fails(folder):
    """The bound's hourly rows hold only a saving; any other figure fails ``hourly``."""
    edit_hourly(folder, "bound", "avg_detour_m", lambda v: 123.0)
    assert_fails(folder, "hourly", "avg_detour_m reported 123.0, recomputed nan", run="bound")


def test_an_invented_hour_fails(folder):
    """hourly.csv has a row per hour in which the run's orders request, no other."""

    def add(t):
        row = t[t["run"] == "mb"].iloc[[0]].assign(hour=5)
        return pd.concat([t, row])

    edit_csv(folder / "hourly.csv", add)
    assert_fails(folder, "hourly", "hourly.csv has hours", run="mb")


def test_hourly_rows_of_an_oracle_fail(folder):
    """Only strategy runs and the bound have hourly rows; an oracle's rows fail the folder's ``hourly``."""
    edit_csv(folder / "hourly.csv", lambda t: pd.concat([t, t[t["run"] == "mb"].assign(run="oracle1")]))
    assert_fails(folder, "hourly", "hourly.csv has rows of run 'oracle1'")


# ------------------------------------------------------------------ report.md
def test_a_number_edited_in_report_md_alone_fails(folder):
    """The KPI tables of report.md are the rendering of kpis.csv: an edited number fails ``report``."""
    path = folder / "report.md"
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("| Total distance saving"))
    cells = lines[k].split(" | ")
    cells[1] = "999.9"
    lines[k] = " | ".join(cells)
    path.write_text("\n".join(lines) + "\n")
    assert_fails(folder, "report", "report.md shows Total distance saving due to ride-pooling (km): 999.9 | ")


def test_a_row_deleted_from_report_md_is_reported_as_not_compared(folder):
    """A row missing from report.md shows nothing false: ``report`` says it was not compared, not failed."""
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


def test_the_best_known_ratio_row_under_its_older_label_is_still_compared(folder):
    """Without a clairvoyant run the row says "best run here"; a report.md written when it said "best known
    schedule" is compared on the same cells: unchanged it passes, an edited cell fails."""
    path = folder / "report.md"
    now, before = (
        "| Ratio to the best run here (saving / best saving of these runs) |",
        "| Competitive ratio (saving / best known schedule) |",
    )
    assert now in path.read_text()
    path.write_text(path.read_text().replace(now, before))
    assert "report" not in violations(folder)
    (found,) = check_tree(folder)
    assert "best" not in found.folder_check.skipped.get("report", "")
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith(before))
    cells = lines[k].split(" | ")
    cells[1] = "0.999"
    lines[k] = " | ".join(cells)
    path.write_text("\n".join(lines) + "\n")
    assert_fails(
        folder, "report", "report.md shows Ratio to the best run here (saving / best saving of these runs): 0.999"
    )


# ------------------------------------------------------------------ decision time
@pytest.mark.parametrize("kpi", ["decision_p50_s", "decision_p95_s", "decision_max_s", "rounds_over_dt"])
def test_a_decision_time_kpi_edited_fails(folder, kpi):
    """The decision-time KPIs are recomputed from rounds.csv.gz: an edited one fails ``kpi``."""
    set_kpi(folder, "mb", kpi, nudge)
    assert_fails(folder, "kpi", f"KPI {kpi}: reported", run="mb")


def test_decision_times_are_the_rounds_table(folder):
    """The writer's definition (rpbench.results.metrics) and the checker's agree on the folder's rounds."""
    from rpbench.results.metrics import DECISION_KPIS, decision_kpis
    from rpbench.results.store import read_meta

    rounds = pd.read_csv(folder / "rounds.csv.gz")
    reported = pd.read_csv(folder / "kpis.csv").set_index(["run", "kpi"])["value"]
    dt = read_meta(folder)["params"]["dt_s"]
    for run in ("mb", "fl"):
        expected = decision_kpis(rounds[rounds["run"] == run], dt)
        assert [reported[(run, k)] for k in DECISION_KPIS] == pytest.approx([expected[k] for k in DECISION_KPIS])
    assert (
        reported[("mb", "decision_p50_s")] <= reported[("mb", "decision_p95_s")] <= reported[("mb", "decision_max_s")]
    )


def test_a_folder_from_before_decision_times_is_said_not_failed(folder):
    edit_csv(folder / "kpis.csv", lambda t: t[~t["kpi"].str.startswith(("decision_", "rounds_over"))])
    assert "kpi" not in violations(folder)


# ------------------------------------------------------------------ decision budget
@pytest.fixture(scope="module")
def budget_run(tmp_path_factory) -> Path:
    """A small clean folder run with a decision budget no round meets: every round is flagged."""
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=3), ["mb", "rtv", "oracle1"], decision_budget_s=1e-9)
    folder = run_comparison(spec, tmp_path_factory.mktemp("budget") / "clean", progress=False).folder
    return folder


@pytest.fixture
def budget_copy(budget_run, tmp_path) -> Path:
    return copy(budget_run, tmp_path)


def set_flag(folder: Path, run: str, value) -> None:
    """Set the over_budget flag of the run's first round to ``value``."""

    def edit(table):
        table["over_budget"] = table["over_budget"].astype(object)
        table.loc[table.index[table["run"] == run][0], "over_budget"] = value

    edit_csv(folder / "rounds.csv.gz", edit)


def test_a_folder_with_a_budget_checks_clean(budget_run, capsys):
    found = assert_passes(budget_run, capsys)
    mb = next(rc for rc in found[0].runs if rc.run == "mb")
    assert mb.checked["budget_rounds"] > 0


def test_a_tampered_budget_count_fails_kpi(budget_copy, capsys):
    set_kpi(budget_copy, "mb", "rounds_over_budget", lambda v: float(v) - 1)
    assert_fails(budget_copy, "kpi", "KPI rounds_over_budget: reported", run="mb")
    assert cli(["check", str(budget_copy)], capsys)[0] == 1


def test_a_missing_budget_count_fails_kpi(budget_copy):
    edit_csv(budget_copy / "kpis.csv", lambda t: t[~((t["run"] == "rtv") & (t["kpi"] == "rounds_over_budget"))])
    assert_fails(budget_copy, "kpi", "KPI rounds_over_budget is not reported", run="rtv")


@pytest.mark.parametrize(
    "value, fragment",
    [
        (False, "1 round(s) of rounds.csv.gz flagged over_budget against their decision time and the 1e-09 s budget"),
        ("maybe", "over_budget holds 'maybe', not True/False"),
    ],
)
def test_a_tampered_over_budget_flag_fails_decision_budget(budget_copy, value, fragment):
    set_flag(budget_copy, "rtv", value)
    found = assert_fails(budget_copy, "decision-budget", fragment, run="rtv")
    assert "kpi" not in found  # the count is the decision times', which are untouched


def test_a_dropped_over_budget_column_fails_decision_budget(budget_copy):
    edit_csv(budget_copy / "rounds.csv.gz", lambda t: t.drop(columns="over_budget"))
    assert_fails(budget_copy, "decision-budget", "rounds.csv.gz lacks the over_budget column", run="mb")


def test_a_raised_budget_in_meta_json_fails(budget_copy):
    """Every round is within a budget of 1e9 s: the reported count and the flags no longer hold."""
    edit_meta(budget_copy, lambda meta: meta.update(decision_budget_s=1e9))
    assert_fails(budget_copy, "kpi", "KPI rounds_over_budget: reported", run="mb")
    assert_fails(budget_copy, "decision-budget", "flagged over_budget", run="mb")


@pytest.mark.parametrize("budget", ["abc", 0, -1, True])
def test_a_malformed_budget_in_meta_json_fails_decision_budget(budget_copy, budget):
    edit_meta(budget_copy, lambda meta: meta.update(decision_budget_s=budget))
    found = assert_fails(budget_copy, "decision-budget", "is not a finite number of seconds > 0", run="mb")
    assert "kpi" not in found


def test_a_budget_removed_from_meta_json_fails_its_kpi_and_column(budget_copy):
    edit_meta(budget_copy, lambda meta: meta.pop("decision_budget_s"))
    assert_fails(budget_copy, "kpi", "KPI rounds_over_budget is reported but meta.json records no decision budget")
    assert_fails(budget_copy, "decision-budget", "rounds.csv.gz has an over_budget column but meta.json records")


def test_a_folder_without_a_budget_needs_neither_kpi_nor_column(clean_copy):
    """A folder of before budgets (or run without one) checks clean; a budget KPI added to it fails."""
    assert "over_budget" not in pd.read_csv(clean_copy / "rounds.csv.gz").columns
    assert_passes(clean_copy)
    edit_csv(
        clean_copy / "kpis.csv",
        lambda t: pd.concat([t, pd.DataFrame([{"run": "mb", "kpi": "rounds_over_budget", "value": 0.0}])]),
    )
    assert_fails(clean_copy, "kpi", "KPI rounds_over_budget is reported but meta.json records no decision budget")
