"""The competitive ratios, LB and the bracket [LB, U] of a folder, edited: each fails ``competitive-ratio``.

LB is recomputed from the simulated runs' event logs, so a consistent rewrite of every derived row and of
meta.json's record still fails.
"""

from __future__ import annotations

import json

import pandas as pd
import pytest

from check.tamper import assert_fails, assert_passes, copy, edit_csv, edit_meta, set_kpi, violations


def nudge(value):
    return 1.0 if pd.isna(value) else float(value) * 1.01 + 0.01


@pytest.fixture
def seer_copy(seers, tmp_path):
    return copy(seers, tmp_path)


def test_the_clean_folder_records_its_best_known_schedule(seers):
    assert_passes(seers)
    meta = json.loads((seers / "meta.json").read_text())
    kpis = pd.read_csv(seers / "kpis.csv").set_index(["run", "kpi"])["value"]
    simulated = ["mb", "hindsight", "fl"]
    savings = {r: kpis[(r, "total_saving_km")] for r in simulated}
    best = max(savings, key=savings.__getitem__)
    assert meta["best_known"] == {"run": best, "saving_km": savings[best]}
    assert kpis[(best, "competitive_ratio_best_known")] == 1.0
    assert kpis[("bound", "best_known_saving_km")] == savings[best]
    assert kpis[("bound", "bound_over_best_known")] == pytest.approx(kpis[("bound", "total_saving_km")] / savings[best])
    for run in simulated:  # the interval: saving / U <= saving / OPT <= saving / LB
        assert kpis[(run, "competitive_ratio_bound")] <= kpis[(run, "competitive_ratio_best_known")]
    assert ("bound", "competitive_ratio_bound") not in kpis.index  # an offline run has no ratio


@pytest.mark.parametrize(
    "run, kpi",
    [
        ("mb", "competitive_ratio_bound"),
        ("mb", "competitive_ratio_best_known"),
        ("mb", "saving_over_oracle1"),
        ("hindsight", "competitive_ratio_best_known"),
        ("fl", "saving_over_oracle1"),
        ("bound", "best_known_saving_km"),
        ("bound", "bound_over_best_known"),
    ],
)
def test_every_derived_row_edited_fails_by_name(seer_copy, run, kpi):
    set_kpi(seer_copy, run, kpi, nudge)
    assert_fails(seer_copy, "competitive-ratio", f"KPI {kpi}: reported", run=run)


@pytest.mark.parametrize("kpi", ["competitive_ratio_best_known", "saving_over_oracle1"])
def test_a_deleted_ratio_row_fails(seer_copy, kpi):
    edit_csv(seer_copy / "kpis.csv", lambda t: t[~((t["run"] == "mb") & (t["kpi"] == kpi))])
    assert_fails(seer_copy, "competitive-ratio", f"KPI {kpi} is not reported", run="mb")


def test_a_ratio_of_an_offline_run_fails(seer_copy):
    """Offline runs are no schedules of the simulator: they have no ratio."""
    row = pd.DataFrame([{"run": "oracle1", "kpi": "competitive_ratio_bound", "value": 0.5}])
    edit_csv(seer_copy / "kpis.csv", lambda t: pd.concat([t, row]))
    assert_fails(seer_copy, "kpi", "KPI competitive_ratio_bound in kpis.csv is not a KPI", run="oracle1")


def test_another_run_named_the_best_known_schedule_fails(seer_copy):
    edit_meta(seer_copy, lambda m: m["best_known"].update(run="mb"))
    assert_fails(seer_copy, "competitive-ratio", "names 'mb' as the best known schedule", run="(folder)")


def test_a_removed_best_known_record_fails(seer_copy):
    edit_meta(seer_copy, lambda m: m.update(best_known=None))
    assert_fails(seer_copy, "competitive-ratio", "best_known is None", run="(folder)")


def test_a_raised_lb_written_consistently_everywhere_fails(seer_copy):
    """LB claimed 10 % higher in every derived row and in meta.json, consistently: the runs' event logs give
    the true LB, so every rewritten row fails."""
    meta = json.loads((seer_copy / "meta.json").read_text())
    true, lb = meta["best_known"]["saving_km"], meta["best_known"]["saving_km"] * 1.1

    def rewrite(t):
        t["value"] = t["value"].astype(float)
        ratio = t["kpi"] == "competitive_ratio_best_known"
        t.loc[ratio, "value"] *= true / lb
        t.loc[(t["run"] == "bound") & (t["kpi"] == "best_known_saving_km"), "value"] = lb
        bound = t.loc[(t["run"] == "bound") & (t["kpi"] == "total_saving_km"), "value"].iloc[0]
        t.loc[(t["run"] == "bound") & (t["kpi"] == "bound_over_best_known"), "value"] = bound / lb

    edit_csv(seer_copy / "kpis.csv", rewrite)
    edit_meta(seer_copy, lambda m: m["best_known"].update(saving_km=lb))
    found = violations(seer_copy)
    messages = " ".join(found["competitive-ratio"])
    for fragment in ("mb: KPI competitive_ratio_best_known", "bound: KPI best_known_saving_km", "best known saving"):
        assert fragment in messages, messages


def test_a_folder_of_an_older_rpbench_is_checked_for_what_it_reports(seer_copy):
    """Written before rpbench recorded LB: no best-known record, no LB rows; the bound's ratio is still held."""
    edit_meta(seer_copy, lambda m: m.pop("best_known"))
    new = ["competitive_ratio_best_known", "saving_over_oracle1", "best_known_saving_km", "bound_over_best_known"]
    edit_csv(seer_copy / "kpis.csv", lambda t: t[~t["kpi"].isin(new)])
    results = assert_passes(seer_copy)
    assert (
        "written before rpbench recorded the best known schedule"
        in results[0].folder_check.skipped["competitive-ratio"]
    )
    set_kpi(seer_copy, "mb", "competitive_ratio_bound", nudge)
    assert_fails(seer_copy, "competitive-ratio", "KPI competitive_ratio_bound: reported", run="mb")
