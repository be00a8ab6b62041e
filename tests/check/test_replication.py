"""The replication folder audit: what it recomputes from a run's passenger records, what it catches, and the
verdict ``rpbench check`` gives a replication folder."""

import gzip
import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from rpbench.check import check_tree
from rpbench.check.replication import SKIPPED, audit_run
from rpbench.cli import main
from rpbench.files.paths import find_data_dir
from rpbench.replication.folder import file_manifest
from rpbench.results.layout import engine_folder, records_file


def records() -> pd.DataFrame:
    # A pair (orders 1, 2 on vehicle 0; solo 5,000 and 3,000 m; rides 5,000 and 3,000; shared 3,000) and a solo order.
    return pd.DataFrame(
        {
            "order_id": [1, 2, 3],
            "vehicle": [0, 0, 1],
            "assign_s": [10.0, 20.0, 10.0],
            "wait_s": [5.0, 5.0, 5.0],
            "pickup_m": [1000.0, 0.0, 500.0],
            "pooled": [True, True, False],
            "partner": [2, 1, -1],
            "detour_m": [0.0, 0.0, float("nan")],
            "shared_m": [3000.0, 3000.0, float("nan")],
            "ride_m": [5000.0, 3000.0, 4000.0],
            "request_s": [5.0, 15.0, 5.0],
            "patience_s": [90.0, 90.0, 90.0],
            "solo_m": [5000.0, 3000.0, 4000.0],
        }
    )


def row(**changes) -> dict:
    base = {
        "served": 3,
        "pooled_passengers": 2,
        "response_denominator": 4,
        "response_rate": 0.75,
        "pairing_ratio": 2 / 3,
        "total_saving_km": 3.0,
        "avg_detour_m": 0.0,
    }
    base.update(changes)
    return base


def test_a_consistent_run_passes():
    """Records that agree with the reported row pass both checks."""
    bad, checked = audit_run(records(), row())
    assert bad == {} and checked["assignment"] > 0 and checked["accounting"] > 0


def test_a_wrong_reported_saving_is_named():
    """The total saving is recomputed from the pairs' records: a wrong reported one fails ``accounting``."""
    bad, _ = audit_run(records(), row(total_saving_km=4.0))
    assert "accounting" in bad and "total_saving_km" in bad["accounting"][0]


def test_a_passenger_served_twice_and_a_one_sided_partner_are_named():
    """A passenger is served once, and partners name each other."""
    rec = records()
    rec.loc[2, "order_id"] = 1
    bad, _ = audit_run(rec, row())
    assert any("served twice" in m for m in bad["assignment"])
    rec = records()
    rec.loc[1, "partner"] = 3
    bad, _ = audit_run(rec, row())
    assert any("not mutual" in m for m in bad["assignment"])


def test_a_two_request_trip_is_one_assignment_but_two_strangers_are_not():
    """A vehicle takes one passenger per round, or one two-request trip of mutual partners."""
    rec = records()
    rec.loc[1, ["assign_s", "request_s"]] = [10.0, 5.0]  # RTV: both partners taken by vehicle 0 in one round
    assert audit_run(rec, row())[0] == {}
    rec.loc[2, ["vehicle", "assign_s"]] = [0, 10.0]
    bad, _ = audit_run(rec, row())
    assert any("not one trip" in m for m in bad["assignment"])


def replication_folder(folder, rows, records=None):
    """A ``rpbench replicate`` folder: meta.json, runs.csv with ``rows``, and passenger records per run."""
    folder.mkdir()
    (folder / "meta.json").write_text(json.dumps({"kind": "replication"}))
    if rows is not None:
        pd.DataFrame(rows).to_csv(folder / "runs.csv", index=False)
    for (date, strategy, engine), rec in (records or {}).items():
        path = records_file(folder, date, strategy, engine)
        path.parent.mkdir(exist_ok=True)
        rec.to_csv(path, index=False)
    return folder


def test_a_replication_folder_is_audited_run_by_run_and_says_what_it_skips(tmp_path):
    """A run with records is audited (trajectory checks skipped by name); the others are skipped with why,
    and a run none of whose checks could be made is SKIPPED, never OK."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    folder = replication_folder(
        tmp_path / "replication",
        [authors, {**authors, "engine": "rpbench"}, {**authors, "engine": "authors-no-teleport"}],
        {("2017-05-01", "mb", "authors"): records()},
    )
    (found,) = check_tree(folder)
    assert found.status == "ok" and [c.run for c in found.runs] == [
        "2017-05-01/mb/authors",
        "2017-05-01/mb/rpbench",
        "2017-05-01/mb/authors-no-teleport",
    ]
    audited, own, unrecorded = found.runs
    assert audited.checked["assignment"] > 0 and audited.skipped == SKIPPED and audited.status == "ok"
    assert set(own.skipped) == {"engine-rows"} and set(unrecorded.skipped) == {"assignment", "accounting"}
    assert own.status == unrecorded.status == "skipped"
    assert found.folder_check is not None and "manifest" in found.folder_check.skipped
    rows = [{**authors, "total_saving_km": 4.0}]
    folder = replication_folder(tmp_path / "wrong", rows, {("2017-05-01", "mb", "authors"): records()})
    (found,) = check_tree(folder)
    assert found.status == "failed" and "total_saving_km" in found.runs[0].violations["accounting"][0]


def test_skipped_runs_print_as_skipped(tmp_path, capsys):
    """``rpbench check`` prints a run whose every check was skipped as SKIPPED, not OK."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors-no-teleport", **row()}
    folder = replication_folder(tmp_path / "replication", [authors])
    assert main(["check", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "2017-05-01/mb/authors-no-teleport: SKIPPED (no check could be made)" in out and ": OK ()" not in out


def test_deleted_records_of_an_authors_run_fail_by_name(tmp_path):
    """The replication writes the records of every ``authors`` run: one missing fails ``records``, named."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    (found,) = check_tree(replication_folder(tmp_path / "replication", [authors]))
    assert found.status == "failed"
    (message,) = found.runs[0].violations["records"]
    assert "records/2017-05-01_mb_authors.csv.gz is missing" in message


def test_records_without_a_column_or_a_text_kpi_fail_by_name(tmp_path):
    """Records lacking a column the audit reads fail ``records``; a text value in runs.csv fails ``accounting``
    (no traceback for either)."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    folder = replication_folder(
        tmp_path / "no-partner", [authors], {("2017-05-01", "mb", "authors"): records().drop(columns="partner")}
    )
    (found,) = check_tree(folder)
    (message,) = found.runs[0].violations["records"]
    assert found.status == "failed" and "lacks the column(s) partner" in message
    text = {**authors, "total_saving_km": "many"}
    (found,) = check_tree(replication_folder(tmp_path / "text", [text], {("2017-05-01", "mb", "authors"): records()}))
    assert found.status == "failed"
    assert any("runs.csv shows the text 'many'" in m for m in found.runs[0].violations["accounting"])


@pytest.mark.parametrize("date", ["../../outside", "/tmp/outside", "2017-05-01/../../x"])
def test_a_date_leading_outside_the_folder_fails_paths(tmp_path, date):
    """A date (or strategy, engine) read from runs.csv never names a file outside the folder."""
    outside = tmp_path / "outside_mb_authors.csv.gz"
    records().to_csv(outside, index=False)  # a file the edited name would point to
    authors = {"date": date, "strategy": "mb", "engine": "authors", **row()}
    (found,) = check_tree(replication_folder(tmp_path / "replication", [authors]))
    assert found.status == "failed" and "paths" in found.runs[0].violations
    assert "assignment" not in found.runs[0].checked


def test_a_records_link_out_of_the_folder_fails_paths(tmp_path):
    """A records file that is a symbolic link to a file outside the folder is not read."""
    outside = tmp_path / "elsewhere.csv.gz"
    records().to_csv(outside, index=False)
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    folder = replication_folder(tmp_path / "replication", [authors])
    path = records_file(folder, "2017-05-01", "mb", "authors")
    path.parent.mkdir()
    path.symlink_to(outside)
    (found,) = check_tree(folder)
    assert "leads outside the folder" in found.runs[0].violations["paths"][0]


def with_manifest(folder: Path) -> Path:
    meta = json.loads((folder / "meta.json").read_text())
    meta["manifest"] = {"files": file_manifest(folder)}
    (folder / "meta.json").write_text(json.dumps(meta))
    return folder


def test_the_manifest_names_edited_deleted_added_and_outside_files(tmp_path):
    """With meta.json's manifest, an edited or deleted file, a file added under records/ and a listed path
    leading outside the folder each fail by name."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    recs = {("2017-05-01", "mb", "authors"): records(), ("2017-05-01", "rtv", "authors"): records()}
    rows = [authors, {**authors, "strategy": "rtv"}]
    folder = with_manifest(replication_folder(tmp_path / "replication", rows, recs))
    (found,) = check_tree(folder)
    assert found.status == "ok" and found.folder_check.checked["files"] == 3
    (folder / "runs.csv").write_text((folder / "runs.csv").read_text() + "\n")
    records_file(folder, "2017-05-01", "rtv", "authors").unlink()
    records().to_csv(records_file(folder, "2017-05-02", "mb", "authors"), index=False)
    meta = json.loads((folder / "meta.json").read_text())
    meta["manifest"]["files"]["../elsewhere"] = "0" * 64
    (folder / "meta.json").write_text(json.dumps(meta))
    (found,) = check_tree(folder)
    fc = found.folder_check
    messages = " | ".join(fc.violations["manifest"])
    assert "runs.csv is not the file the replication wrote" in messages
    assert "records/2017-05-01_rtv_authors.csv.gz listed in meta.json is missing" in messages
    assert "records/2017-05-02_mb_authors.csv.gz is not a file the replication wrote" in messages
    assert "'../elsewhere'" in fc.violations["paths"][0]
    assert "records" in found.runs[1].violations


def test_a_replication_folder_without_runs_csv_is_unreadable(tmp_path):
    """A replication folder without its runs.csv cannot be checked: one error line."""
    (found,) = check_tree(replication_folder(tmp_path / "replication", None))
    assert found.status == "unreadable" and "has no runs.csv" in found.error


# ------------------------------------------------ a real folder (needs the Haikou data)
@pytest.fixture(scope="module")
def replicated(tmp_path_factory) -> Path:
    """``rpbench replicate`` on 2017-05-01, MB, with rpbench's own engine (skipped without the data)."""
    data = find_data_dir()
    if data is None:
        pytest.skip("Haikou data folder not found (set RPBENCH_DATA)")
    out = tmp_path_factory.mktemp("replicate") / "rep"
    argv = ["replicate", "--data", str(data), "--date", "2017-05-01", "--strategies", "mb", "--no-ablation"]
    assert main([*argv, "--json", "--out", str(out)]) == 0
    return out


@pytest.fixture
def rep(replicated, tmp_path) -> Path:
    target = tmp_path / "rep"
    shutil.copytree(replicated, target, symlinks=True)
    return target


def rehash(folder: Path) -> None:
    """Recompute meta.json's manifest, as someone hiding an edit would: the other checks must still catch it."""
    meta = json.loads((folder / "meta.json").read_text())
    meta["manifest"]["files"] = file_manifest(folder)
    (folder / "meta.json").write_text(json.dumps(meta))


def verdict(folder: Path) -> dict[str, dict[str, list[str]]]:
    (found,) = check_tree(folder)
    assert found.error is None, found.error
    return {c.run: c.violations for c in found.checks if c.violations}


def test_an_untouched_replicate_folder_passes_and_checks_rpbench_s_runs(replicated):
    """Every file is listed, the report re-renders, rpbench's own runs pass the full checker."""
    (found,) = check_tree(replicated)
    assert found.status == "ok"
    runs = {c.run: c for c in found.runs}
    own = runs["2017-05-01/mb/rpbench"]
    assert own.status == "ok" and own.checked["engine_rows"] > 0 and own.checked["trajectory_steps"] > 0
    assert found.folder_check.checked["files"] > 5 and found.folder_check.checked["report_lines"] > 0


@pytest.mark.parametrize("engine", ["rpbench", "rpbench-peak"])
def test_an_edited_engine_row_fails_engine_rows(rep, engine):
    """rpbench's own rows are its results folders' KPIs: a saving doubled in runs.csv fails, re-hashed or not."""
    frame = pd.read_csv(rep / "runs.csv")
    frame.loc[frame["engine"] == engine, "total_saving_km"] *= 2
    frame.to_csv(rep / "runs.csv", index=False)
    rehash(rep)
    found = verdict(rep)
    assert any("total_saving_km" in m for m in found[f"2017-05-01/mb/{engine}"]["engine-rows"])
    assert "report" in found["(folder)"]  # the report's tables no longer render from runs.csv: report.md
    # unchanged shows the old saving


def test_an_edited_engine_folder_fails_the_full_checker(rep):
    """An engine run's kpis.csv edited with runs.csv to match: the full checker recomputes the KPI."""
    kpis_csv = engine_folder(rep, "2017-05-01", "mb", "rpbench") / "kpis.csv"
    kpis = pd.read_csv(kpis_csv)
    sel = kpis["kpi"] == "total_saving_km"
    kpis.loc[sel, "value"] = kpis.loc[sel, "value"].astype(float) * 2
    kpis.to_csv(kpis_csv, index=False)
    rehash(rep)
    found = verdict(rep)
    assert "kpi" in found["2017-05-01/mb/rpbench"]


def test_an_edited_report_table_fails_report(rep):
    """A number edited in report.md alone fails ``manifest``, and ``report`` even with the SHA-256 re-hashed."""
    text = (rep / "report.md").read_text()
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("| mb") or line.startswith("| authors"))
    lines[k] = lines[k].replace("0.", "9.", 1)
    assert lines[k] != text.splitlines()[k]
    (rep / "report.md").write_text("\n".join(lines) + "\n")
    assert any("report.md is not the file" in m for m in verdict(rep)["(folder)"]["manifest"])
    rehash(rep)
    assert "report.md table line" in verdict(rep)["(folder)"]["report"][0]


def test_deleted_records_and_engine_folders_fail_by_name(rep):
    """Records and engine folders deleted (and dropped from the manifest) still fail, each by name."""
    records_file(rep, "2017-05-01", "mb", "authors").unlink()
    shutil.rmtree(engine_folder(rep, "2017-05-01", "mb", "rpbench"))
    found = verdict(rep)
    assert any(
        "2017-05-01_mb_authors.csv.gz listed in meta.json is missing" in m for m in found["(folder)"]["manifest"]
    )
    rehash(rep)
    found = verdict(rep)
    assert "records/2017-05-01_mb_authors.csv.gz is missing" in found["2017-05-01/mb/authors"]["records"][0]
    assert "engines/2017-05-01_mb_rpbench/ is missing" in found["2017-05-01/mb/rpbench"]["engine-rows"][0]


def test_dates_pointing_outside_the_folder_fail_paths(rep, tmp_path):
    """A date edited to lead outside (with a copy of the records waiting there), and a records file turned
    into a link out of the folder: ``paths``, and nothing outside is read."""
    path = records_file(rep, "2017-05-01", "mb", "authors")
    outside = tmp_path / "x"
    outside.mkdir()
    shutil.copy(path, outside / "stolen_mb_authors.csv.gz")
    frame = pd.read_csv(rep / "runs.csv")
    frame.loc[frame["engine"] == "authors", "date"] = "../../x/stolen"
    frame.to_csv(rep / "runs.csv", index=False)
    rehash(rep)
    assert "paths" in verdict(rep)["../../x/stolen/mb/authors"]
    link = tmp_path / "linked"
    shutil.copytree(rep, link, symlinks=True)
    frame.loc[frame["engine"] == "authors", "date"] = "2017-05-01"
    frame.to_csv(link / "runs.csv", index=False)
    target = records_file(link, "2017-05-01", "mb", "authors")
    target.unlink()
    target.symlink_to(outside / "stolen_mb_authors.csv.gz")
    rehash(link)
    found = verdict(link)
    assert "paths" in found["2017-05-01/mb/authors"] and any("symbolic link" in m for m in found["(folder)"]["paths"])
    with gzip.open(outside / "stolen_mb_authors.csv.gz") as fh:  # the file outside is untouched
        assert fh.read(8)
