"""Folders the checker cannot read: ``rpbench check`` exits 2 with one line naming the file and the problem,
never a traceback, never a verdict (exit 1 is kept for a check that failed)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_unreadable,
    cli,
    edit_csv,
    edit_meta,
    edit_npz,
    truncate,
)

base, folder = helpers.base, helpers.folder  # fixtures (clean folders built once per module)


def trunc(rel, keep=0.5):
    return lambda f: truncate(f / rel, keep)


def delete(rel):
    return lambda f: (f / rel).unlink()


def drop_column(rel, column):
    return lambda f: edit_csv(f / rel, lambda t: t.drop(columns=[column]))


def text_in(rel, column, row=3, text="abc"):
    def fn(f):
        def edit(t):
            t[column] = t[column].astype(object)
            t.loc[row, column] = text

        edit_csv(f / rel, edit)

    return fn


def drop_array(rel, key):
    return lambda f: edit_npz(f / rel, lambda z: z.pop(key))


def meta(fn):
    return lambda f: edit_meta(f, fn)


def disconnect(f):
    """Remove every arc leaving node 0: the network is no longer strongly connected."""

    def fn(z):
        keep = z["arc_tail"] != 0
        for key in ("arc_tail", "arc_head", "arc_length_m", "arc_link_id"):
            z[key] = z[key][keep]

    edit_npz(f / "network.npz", fn)


EVENTS, TRAJ, PAIRS = "runs/mb/events.csv.gz", "runs/rtv/trajectories.npz", "runs/oracle1/pairs.csv.gz"

CASES = {
    "truncated events": (trunc(EVENTS), "events.csv.gz' is corrupt or not a CSV table"),
    "truncated trajectories": (trunc(TRAJ), "trajectories.npz' is corrupt or not an npz archive"),
    "truncated network": (trunc("network.npz", 0.7), "network.npz' is corrupt or not an npz archive"),
    "truncated oracle pairs": (trunc(PAIRS, 0.4), "pairs.csv.gz' is corrupt or not a CSV table"),
    "truncated orders": (trunc("orders.csv.gz", 0.6), "orders.csv.gz' is corrupt or not a CSV table"),
    "garbage instead of an npz": (
        lambda f: (f / TRAJ).write_bytes(b"not a zip archive"),
        "trajectories.npz' is corrupt or not an npz archive",
    ),
    "an empty events file": (lambda f: (f / EVENTS).write_bytes(b""), "events.csv.gz' is empty (not even a header"),
    "a missing trajectory array": (drop_array(TRAJ, "odo_m"), "trajectories.npz' lacks the array(s) odo_m"),
    "a missing network array": (
        drop_array("network.npz", "arc_length_m"),
        "network.npz' lacks the array(s) arc_length_m",
    ),
    "a missing events column": (drop_column(EVENTS, "partner"), "events.csv.gz' lacks the column(s) partner"),
    "a missing orders column": (drop_column("orders.csv.gz", "patience_s"), "lacks the column(s) patience_s"),
    "a missing pairs column": (drop_column(PAIRS, "saving_m"), "pairs.csv.gz' lacks the column(s) saving_m"),
    "a missing kpis column": (drop_column("kpis.csv", "value"), "kpis.csv' lacks the column(s) value"),
    "text in an event time": (text_in(EVENTS, "t_s"), "column 't_s' holds 'abc', not a number (row 5)"),
    "text in a request time": (text_in("orders.csv.gz", "request_s"), "column 'request_s' holds 'abc'"),
    "text in a pair saving": (text_in(PAIRS, "saving_m", row=1), "column 'saving_m' holds 'abc'"),
    "a fractional order id": (text_in(EVENTS, "order", text=2.5), "column 'order' holds missing or non-integer"),
    "a missing request time": (
        text_in("orders.csv.gz", "request_s", text=np.nan),
        "column 'request_s' holds NaN or infinite values",
    ),
    "an origin outside the network": (
        text_in("orders.csv.gz", "origin", text=5000),
        "column 'origin' names a node outside the network's 0..143",
    ),
    "an arc to a node that does not exist": (
        lambda f: edit_npz(f / "network.npz", lambda z: z["arc_head"].__setitem__(0, 999)),
        "an arc ends at a node index outside 0..143",
    ),
    "a disconnected network": (disconnect, "is not strongly connected"),
    "meta.json without params": (meta(lambda m: m.pop("params")), "has no params"),
    "meta.json with an extra param": (
        meta(lambda m: m["params"].__setitem__("surge", 2.0)),
        "params hold unknown parameter(s) surge",
    ),
    "meta.json missing a param": (
        meta(lambda m: m["params"].pop("max_detour_m")),
        "params lack max_detour_m (the checker assumes no default)",
    ),
    "a param that is text": (
        meta(lambda m: m["params"].__setitem__("max_detour_m", "far")),
        "parameter max_detour_m = 'far' is not a finite number",
    ),
    "meta.json without runs": (meta(lambda m: m.pop("runs")), "has no runs record"),
    "an oracle without its rules": (
        meta(lambda m: m["runs"]["oracle2"].pop("rules")),
        "oracle run 'oracle2' lacks its pair rules",
    ),
    "meta.json that is not JSON": (lambda f: (f / "meta.json").write_text('{"params": '), "is not valid JSON"),
    "meta.json holding a list": (lambda f: (f / "meta.json").write_text("[1, 2]"), "does not hold a JSON object"),
    "kpis.csv missing": (delete("kpis.csv"), "kpis.csv' is missing"),
    "meta.json missing": (delete("meta.json"), "is not an rpbench results folder (no meta.json)"),
    "events missing": (delete(EVENTS), "events.csv.gz' is missing"),
    "trajectories missing": (delete(TRAJ), "trajectories.npz' is missing"),
    "oracle pairs missing": (delete(PAIRS), "pairs.csv.gz' is missing"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_an_unreadable_folder_exits_2_with_one_line(folder, case, capsys):
    tamper, fragment = CASES[case]
    tamper(folder)
    assert_unreadable(folder, fragment, capsys)


def test_a_missing_folder(tmp_path, capsys):
    assert_unreadable(tmp_path / "nowhere", "does not exist", capsys)


def test_json_reports_the_unreadable_folder_and_still_checks_the_others(base, folder, capsys):
    truncate(folder / EVENTS)
    code, out, err = cli(["check", "--json", str(base), str(folder)], capsys)
    report = json.loads(out)
    assert code == 2 and report["status"] == "unreadable" and report["exit_status"] == 2 and not report["ok"]
    assert report["folders"][str(base)]["mb"]["status"] == "ok" and report["folders"][str(folder)] == {}
    assert "is corrupt" in report["unreadable"][str(folder)] and err.count("rpbench: error:") == 1


def test_unreadable_wins_over_failed_and_both_are_reported(base, folder, tmp_path, capsys):
    import shutil

    failing = tmp_path / "failing"
    shutil.copytree(base, failing)
    edit_csv(
        failing / "kpis.csv",
        lambda t: t.assign(value=np.where((t["run"] == "mb") & (t["kpi"] == "served"), 1.0, t["value"])),
    )
    delete("kpis.csv")(folder)
    code, out, err = cli(["check", str(failing), str(folder)], capsys)
    assert code == 2 and "[kpi]" in out and f"== {folder}" in out and "kpis.csv' is missing" in err
    assert "Traceback" not in out + err
    assert cli(["check", str(failing)], capsys)[0] == 1


def test_publish_refuses_an_unreadable_folder_in_one_line(folder, tmp_path, capsys):
    trunc(TRAJ)(folder)
    code, out, err = cli(["publish", str(folder), str(tmp_path / "pub")], capsys)
    assert code == 2 and err.count("\n") == 1 and "cannot be checked" in err and "not published" in err
    assert not (tmp_path / "pub").exists()


def test_reading_a_kpi_file_of_text_is_not_a_crash(folder, capsys):
    """kpis.csv is what is checked, not an input: a text value is a failed ``kpi`` check (exit 1)."""
    edit_csv(folder / "kpis.csv", lambda t: t.assign(value=t["value"].astype(object).where(t["run"] != "rtv", "x")))
    code, out, err = cli(["check", str(folder)], capsys)
    assert code == 1 and "rtv: FAILED" in out and "is not a number" in out and err == ""


def test_a_published_light_copy_says_where_its_verdict_is(base, tmp_path, capsys):
    from rpbench.harness.publish import publish

    dest = publish(base, tmp_path / "published")
    line = assert_unreadable(dest, "is a published light copy without event logs or inputs", capsys)
    assert "check.txt holds the verdict" in line
