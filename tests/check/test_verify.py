"""The entry points: every valid folder rpbench writes passes — 0 pairs, 0 served, an empty hour, a tiny sample,
en-route oracles, an old folder without digest — a missing or unreadable folder is one line, and a folder of
results folders is checked folder by folder."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

from check.tamper import (
    assert_passes,
    assert_unreadable,
    build,
    cli,
    copy,
    edit_events,
    edit_meta,
    run_violations,
    truncate,
    with_empty_hour,
)
from rpbench.check import FOLDER, check_folder, check_tree
from rpbench.cli import main
from rpbench.exceptions import ResultsError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.publish import publish
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


@pytest.fixture(scope="module")
def zero_pairs(tmp_path_factory):
    """Two orders (``rpbench run --scenario toy --sample 0.005``): no run forms a pair."""
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
    """Orders in hours 0 and 2, none in hour 1."""
    request = ScenarioRequest("toy", sample=0.3, seed=2)
    spec = RunSpec.of(request, ["mb", "fl", "bound", "oracle1"], oracle_preset="matching")
    scenario = with_empty_hour(request.build())
    folder = run_comparison(spec, tmp_path_factory.mktemp("gap") / "toy", scenario=scenario, progress=False).folder
    return folder


def test_the_clean_folder_passes_every_check(base, capsys):
    """A clean folder of every kind of run passes every check, its digest covering 3 files, params and 6 runs."""
    results = assert_passes(base, capsys)
    (found,) = results
    assert {c.run for c in found.checks} == {FOLDER, "mb", "rtv", "fl", "bound", "oracle1", "oracle2"}
    assert found.folder_check.checked["digests"] == 3 + 1 + 6 and not found.folder_check.skipped


def test_zero_pairs_pass_check_and_publish(zero_pairs, tmp_path, capsys):
    """A folder without a single pair passes the checker, and publish writes its verdict."""
    assert_passes(zero_pairs, capsys)
    (found,) = check_tree(zero_pairs)
    assert {c.run: c.checked.get("pairs") for c in found.runs if c.run.startswith("oracle")} == {
        "oracle1": 0,
        "oracle2": 0,
    }
    kpis = pd.read_csv(zero_pairs / "kpis.csv").set_index(["run", "kpi"])["value"]
    assert kpis[("bound", "best_known_saving_km")] == 0.0  # LB = 0: the ratio to it is undefined, and checked so
    assert pd.isna(kpis[("mb", "competitive_ratio_best_known")]) and pd.isna(kpis[("bound", "bound_over_best_known")])
    dest = publish(zero_pairs, tmp_path / "pub")
    assert "oracle1: OK" in (dest / "check.txt").read_text()


def test_zero_served_passes(zero_served, capsys):
    """A folder where every order is cancelled (undefined rates and averages) passes."""
    assert_passes(zero_served, capsys)
    (found,) = check_tree(zero_served)
    assert all(c.checked["served"] == 0 for c in found.runs if c.run in ("mb", "rtv"))


def test_an_hour_without_orders_passes(empty_hour, capsys):
    """An hour without orders has no row in hourly.csv, and the folder passes."""
    assert_passes(empty_hour, capsys)
    (found,) = check_tree(empty_hour)
    assert {c.run: c.checked["hours"] for c in found.runs if "hours" in c.checked} == {"mb": 2, "fl": 2, "bound": 2}


def test_en_route_oracles_pass(enroute, capsys):
    """Oracles with en-route pairs, both pick-up orders and the pick-up test pass."""
    assert_passes(enroute, capsys)


def test_an_old_folder_without_digest_or_manifest_passes_and_says_what_it_skipped(base, tmp_path, capsys):
    """A folder written before digests and manifests passes, and the output says the digest was skipped."""
    folder = copy(base, tmp_path)
    edit_meta(folder, lambda m: (m.pop("inputs_digest"), m.pop("manifest")))
    assert_passes(folder)
    code, out, err = cli(["check", str(folder)], capsys)
    assert code == 0 and "[inputs-digest] skipped: meta.json records no inputs digest" in out


def test_check_folder_lists_the_runs_and_the_folder_only_when_it_failed(base, tmp_path):
    """check_folder returns one verdict per run, preceded by the folder's own only when that failed."""
    assert [c.run for c in check_folder(base)] == ["mb", "rtv", "fl", "bound", "oracle1", "oracle2"]
    folder = copy(base, tmp_path)
    shutil.rmtree(folder / "runs" / "oracle2")
    assert next(c.run for c in check_folder(folder)) == FOLDER


def test_a_missing_folder(tmp_path, capsys):
    """A folder that does not exist is one error line, exit 2."""
    assert_unreadable(tmp_path / "nowhere", "does not exist", capsys)


def test_publish_refuses_an_unreadable_folder_in_one_line(folder, tmp_path, capsys):
    """publish checks first: an unreadable folder is not published, and says so in one line."""
    truncate(folder / "runs" / "rtv" / "trajectories.npz")
    code, out, err = cli(["publish", str(folder), str(tmp_path / "pub")], capsys)
    assert code == 2 and err.count("\n") == 1 and "cannot be checked" in err and "not published" in err
    assert not (tmp_path / "pub").exists()


def test_clean_run_passes(clean_run, capsys):
    """A clean folder passes, and ``rpbench check`` exits 0 printing each run OK."""
    assert run_violations(clean_run) == {}
    assert main(["check", str(clean_run)]) == 0
    assert "mb: OK" in capsys.readouterr().out


def test_not_a_results_folder(tmp_path):
    """A folder without meta.json is not a results folder: check_folder raises, ``rpbench check`` exits 2."""
    with pytest.raises(ResultsError, match="no meta.json"):
        check_folder(tmp_path)
    assert main(["check", str(tmp_path / "missing")]) == 2


def test_a_parent_folder_checks_every_run_folder_inside_and_fails_if_one_fails(clean_run, tmp_path, capsys):
    """A plain folder of results folders is checked folder by folder; one failing fails the whole."""
    parent = tmp_path / "days"
    for day in ("d1", "d2"):
        shutil.copytree(clean_run, parent / day)
    assert main(["check", str(parent)]) == 0
    out = capsys.readouterr().out
    assert f"== {parent / 'd1'}" in out and f"== {parent / 'd2'}" in out
    edit_events(parent / "d2", "mb", lambda ev: ev[ev["event"] != "dropoff"])
    assert main(["check", str(parent)]) == 1
