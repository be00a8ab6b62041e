"""The replication folder audit: what it recomputes from a run's passenger records, what it catches, and the
verdict ``rpbench check`` gives a replication folder."""

import json

import pandas as pd

from rpbench.results.check import check_tree
from rpbench.results.check.replication import SKIPPED, audit_run, records_file


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
    """A run with records is audited (trajectory checks skipped by name); the others are skipped with why."""
    authors = {"date": "2017-05-01", "strategy": "mb", "engine": "authors", **row()}
    folder = replication_folder(
        tmp_path / "replication",
        [authors, {**authors, "engine": "rpbench"}, {**authors, "strategy": "rtv"}],
        {("2017-05-01", "mb", "authors"): records()},
    )
    (found,) = check_tree(folder)
    assert found.status == "ok" and [c.run for c in found.runs] == [
        "2017-05-01/mb/authors",
        "2017-05-01/mb/rpbench",
        "2017-05-01/rtv/authors",
    ]
    audited, own, unrecorded = found.runs
    assert audited.checked["assignment"] > 0 and audited.skipped == SKIPPED
    assert set(own.skipped) == {"all"} and set(unrecorded.skipped) == {"assignment", "accounting"}
    rows = [{**authors, "total_saving_km": 4.0}]
    folder = replication_folder(tmp_path / "wrong", rows, {("2017-05-01", "mb", "authors"): records()})
    (found,) = check_tree(folder)
    assert found.status == "failed" and "total_saving_km" in found.runs[0].violations["accounting"][0]


def test_a_replication_folder_without_runs_csv_is_unreadable(tmp_path):
    """A replication folder without its runs.csv cannot be checked: one error line."""
    (found,) = check_tree(replication_folder(tmp_path / "replication", None))
    assert found.status == "unreadable" and "has no runs.csv" in found.error
