"""Every valid folder rpbench writes passes — 0 pairs, 0 served, an empty hour, a tiny sample, en-route
oracles, a sweep, a multi-day folder, an old folder without digest — and a parent folder with a deleted day or
point, or an edited summary table, fails by name."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_fails,
    assert_passes,
    build,
    cli,
    copy,
    edit_csv,
    edit_meta,
    violations,
    with_empty_hour,
    write_fake_haikou,
)
from rpbench.harness.comparison import run_comparison
from rpbench.harness.multiday import run_days
from rpbench.harness.publish import publish
from rpbench.harness.sweep import SweepSpec, expand, run_sweep
from rpbench.results.check import FOLDER, check_folder, check_tree
from rpbench.scenarios import ScenarioRequest, build_scenario

base, enroute = helpers.base, helpers.enroute  # fixtures (clean folders built once per module)


@pytest.fixture(scope="module")
def zero_pairs(tmp_path_factory):
    """The issue's reproduction: `rpbench run --scenario toy --sample 0.005 --strategies mb,oracle1` (2 orders)."""
    return build(
        tmp_path_factory.mktemp("zero") / "toy", ["mb", "rtv", "oracle1", "oracle2", "bound"], sample=0.005, seed=0
    )


@pytest.fixture(scope="module")
def zero_served(tmp_path_factory):
    """R̄ = 1 m: no vehicle is ever close enough, every order is cancelled (NaN rates and averages)."""
    return build(
        tmp_path_factory.mktemp("none") / "toy",
        ["mb", "rtv", "oracle1", "bound"],
        sample=0.05,
        seed=0,
        max_pickup_m=1.0,
    )


@pytest.fixture(scope="module")
def empty_hour(tmp_path_factory):
    scenario = with_empty_hour(build_scenario("toy", sample=0.3, seed=2))
    folder, _ = run_comparison(
        scenario,
        ["mb", "fl", "bound", "oracle1"],
        "highs",
        progress=False,
        out=tmp_path_factory.mktemp("gap") / "toy",
        oracle_solver="matching",
    )
    return folder


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    spec = SweepSpec("check-test", "dt", (10.0, 30.0), ("mb", "rtv"), ("total_saving_km", "response_rate"))
    return run_sweep(
        spec,
        expand("dt", spec.values),
        request=ScenarioRequest("toy", sample=0.2, seed=1),
        preset="highs",
        run_options={},
        out=str(tmp_path_factory.mktemp("sweep") / "dt"),
        workers=1,
        scheduler=None,
        command="test",
    )


@pytest.fixture(scope="module")
def multiday(tmp_path_factory):
    data = write_fake_haikou(tmp_path_factory.mktemp("data") / "haikou")
    return run_days(
        ScenarioRequest("haikou-peak", sample=1.0, data_dir=str(data)),
        ["2017-05-01", "2017-05-02"],
        strategies=["mb", "oracle1"],
        preset="highs",
        run_options={},
        out=str(tmp_path_factory.mktemp("days") / "days"),
        workers=1,
        scheduler=None,
        command="test",
        oracle_solver="matching",
    )


# --------------------------------------------------------------- valid folders
def test_the_clean_folder_passes_every_check(base, capsys):
    results = assert_passes(base, capsys)
    (found,) = results
    assert {c.run for c in found.checks} == {FOLDER, "mb", "rtv", "fl", "bound", "oracle1", "oracle2"}
    assert found.folder_check.checked["digests"] == 3 + 1 + 6 and not found.folder_check.skipped


def test_zero_pairs_pass_check_and_publish(zero_pairs, tmp_path, capsys):
    """0 pairs used to be a TypeError in the checker and in publish."""
    assert_passes(zero_pairs, capsys)
    (found,) = check_tree(zero_pairs)
    assert {c.run: c.checked.get("pairs") for c in found.runs if c.run.startswith("oracle")} == {
        "oracle1": 0,
        "oracle2": 0,
    }
    dest = publish(zero_pairs, tmp_path / "pub")
    assert "oracle1: OK" in (dest / "check.txt").read_text()


def test_zero_served_passes(zero_served, capsys):
    assert_passes(zero_served, capsys)
    (found,) = check_tree(zero_served)
    assert all(c.checked["served"] == 0 for c in found.runs if c.run in ("mb", "rtv"))


def test_an_hour_without_orders_passes(empty_hour, capsys):
    assert_passes(empty_hour, capsys)
    (found,) = check_tree(empty_hour)
    assert {c.run: c.checked["hours"] for c in found.runs if "hours" in c.checked} == {"mb": 2, "fl": 2, "bound": 2}


def test_en_route_oracles_pass(enroute, capsys):
    assert_passes(enroute, capsys)


def test_a_sweep_folder_passes(sweep, capsys):
    results = assert_passes(sweep, capsys)
    assert len(results) == 3 and results[0].folder_check.checked["children"] == 2
    assert results[0].folder_check.checked["sweep"] == 2 * 2 * 19  # points x runs x KPIs


def test_a_multi_day_folder_passes(multiday, capsys):
    results = assert_passes(multiday, capsys)
    assert len(results) == 3 and results[0].folder_check.checked["children"] == 2


def test_an_old_folder_without_digest_or_manifest_passes_and_says_what_it_skipped(base, tmp_path, capsys):
    folder = copy(base, tmp_path)
    edit_meta(folder, lambda m: (m.pop("inputs_digest"), m.pop("manifest")))
    assert_passes(folder)
    code, out, err = cli(["check", str(folder)], capsys)
    assert code == 0 and "[inputs-digest] skipped: meta.json records no inputs digest" in out


def test_json_output_keeps_its_structure_and_adds_the_status(base, tmp_path, capsys):
    folder = copy(base, tmp_path)
    edit_csv(
        folder / "kpis.csv",
        lambda t: t.assign(value=np.where((t["run"] == "fl") & (t["kpi"] == "pairs"), 99.0, t["value"])),
    )
    code, out, _ = cli(["check", "--json", str(base), str(folder)], capsys)
    report = json.loads(out)
    assert code == 1 and report["ok"] is False and report["status"] == "failed" and report["exit_status"] == 1
    assert report["unreadable"] == {}
    clean, bad = report["folders"][str(base)], report["folders"][str(folder)]
    assert clean["mb"] == {**clean["mb"], "ok": True, "status": "ok", "violations": {}, "skipped": {}}
    assert bad["fl"]["status"] == "failed" and "KPI pairs: reported 99.0" in bad["fl"]["violations"]["kpi"][0]


def test_check_folder_lists_the_runs_and_the_folder_only_when_it_failed(base, tmp_path):
    assert [c.run for c in check_folder(base)] == ["mb", "rtv", "fl", "bound", "oracle1", "oracle2"]
    folder = copy(base, tmp_path)
    shutil.rmtree(folder / "runs" / "oracle2")
    assert next(c.run for c in check_folder(folder)) == FOLDER


def test_the_help_states_the_exit_statuses(capsys):
    with pytest.raises(SystemExit):
        cli(["check", "--help"], capsys)
    text = capsys.readouterr().out
    assert (
        "0  every check passed" in text
        and "1  a check failed" in text
        and "2  bad usage, or a folder is unreadable" in text
    )


# ------------------------------------------------------------- parent folders
def test_a_multi_day_folder_with_a_deleted_day_fails(multiday, tmp_path):
    folder = copy(multiday, tmp_path)
    shutil.rmtree(folder / "2017-05-02")
    found = assert_fails(folder, "manifest", "day folder 2017-05-02/ listed in meta.json is missing (deleted?)")
    assert any("by_day.csv: rows" in m for m in found["parent-tables"])


def test_a_sweep_with_a_deleted_point_fails(sweep, tmp_path):
    folder = copy(sweep, tmp_path)
    shutil.rmtree(folder / "dt=30")
    assert_fails(folder, "manifest", "sweep point folder dt=30/ listed in meta.json is missing")


def test_an_old_multi_day_folder_is_held_to_its_dates(multiday, tmp_path):
    """Before meta.json recorded ``children``, its ``dates`` name the day folders."""
    folder = copy(multiday, tmp_path)
    edit_meta(folder, lambda m: m.pop("children"))
    assert_passes(folder)
    shutil.rmtree(folder / "2017-05-01")
    assert_fails(folder, "manifest", "day folder 2017-05-01/ listed in meta.json is missing")


def test_an_edited_per_day_table_fails(multiday, tmp_path):
    folder = copy(multiday, tmp_path)
    edit_csv(
        folder / "by_day.csv",
        lambda t: t.assign(
            value=np.where((t["run"] == "mb") & (t["kpi"] == "served") & (t["date"] == "2017-05-01"), 0.0, t["value"])
        ),
    )
    assert_fails(folder, "parent-tables", "by_day.csv: value of ('2017-05-01', 'mb', 'served') is 0.0")


def test_an_edited_mean_over_days_fails(multiday, tmp_path):
    folder = copy(multiday, tmp_path)
    edit_csv(
        folder / "summary.csv",
        lambda t: t.assign(
            mean=np.where((t["run"] == "mb") & (t["kpi"] == "total_saving_km"), t["mean"] + 1.0, t["mean"])
        ),
    )
    assert_fails(folder, "parent-tables", "summary.csv: mean of ('mb', 'total_saving_km')")


def test_an_edited_sweep_table_fails(sweep, tmp_path):
    folder = copy(sweep, tmp_path)
    edit_csv(
        folder / "sweep.csv",
        lambda t: t.assign(
            value=np.where((t["run"] == "rtv") & (t["kpi"] == "pairs") & (t["label"] == "dt=10"), 1.0, t["value"])
        ),
    )
    assert_fails(folder, "parent-tables", "sweep.csv: value of ('dt=10', 'rtv', 'pairs') is 1.0")


def test_a_day_edited_inside_a_multi_day_folder_fails_that_day(multiday, tmp_path, capsys):
    folder = copy(multiday, tmp_path)
    edit_csv(folder / "2017-05-02" / "runs" / "mb" / "events.csv.gz", lambda ev: ev[ev["event"] != "dropoff"])
    found = violations(folder)
    assert "service" in found
    code, out, _ = cli(["check", str(folder)], capsys)
    assert code == 1 and f"== {folder / '2017-05-02'}" in out
