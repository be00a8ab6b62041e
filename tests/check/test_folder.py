"""The folder's inputs: a file missing, truncated or unparseable, a column missing or not of its kind, meta.json
without its parameters — ``rpbench check`` exits 2 with one line naming the file and the problem, never a
traceback, never a verdict (exit 1 is kept for a check that failed) — and the inputs a verdict rests on (orders,
network, fleet, parameters, run options, the run list) edited or deleted: the run-time digest and manifest catch
what no other check would (a relaxed threshold, a deleted run)."""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest

from check.tamper import (
    assert_fails,
    assert_unreadable,
    edit_csv,
    edit_meta,
    edit_npz,
    truncate,
)


# ---------------------------------------------------------------- unreadable
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

UNREADABLE = {
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


@pytest.mark.parametrize("case", list(UNREADABLE))
def test_an_unreadable_folder_exits_2_with_one_line(folder, case, capsys):
    """An input that cannot be read makes the folder unreadable: exit 2, one line naming file and problem."""
    tamper, fragment = UNREADABLE[case]
    tamper(folder)
    assert_unreadable(folder, fragment, capsys)


def test_a_published_light_copy_is_checked_for_what_it_keeps(base, tmp_path):
    """A published copy of one run (no event logs, no inputs) is checked as a light copy: its verdict, its
    manifest and its report against its kpis.csv; the runs' checks and the digests are skipped, saying why.
    An edit of its kpis.csv alone fails (the report no longer shows it); a verdict edited to FAILED fails."""
    from rpbench.check import check_tree
    from rpbench.check.folder import read_folder
    from rpbench.exceptions import ResultsError
    from rpbench.harness.publish import publish

    dest = publish(base, tmp_path / "published")
    with pytest.raises(ResultsError, match="is a published light copy without event logs or inputs"):
        read_folder(dest)  # the full checker's reader still refuses it, pointing to check.txt
    (found,) = check_tree(dest)
    assert found.status == "ok" and found.folder_check.checked["verdicts"] >= 2
    assert "no parent records the SHA-256" in found.folder_check.skipped["light-copy"]
    assert "keeps no event logs" in found.folder_check.skipped["runs"]
    kpis = pd.read_csv(dest / "kpis.csv")
    row = (kpis["run"] == "mb") & (kpis["kpi"] == "total_saving_km")
    kpis.loc[row, "value"] = kpis.loc[row, "value"] + 100.0
    kpis.to_csv(dest / "kpis.csv", index=False)
    (found,) = check_tree(dest)
    assert found.status == "failed" and "report" in found.folder_check.violations
    verdict = dest / "check.txt"
    verdict.write_text(verdict.read_text().replace("mb: OK", "mb: FAILED"))
    (found,) = check_tree(dest)
    assert "check-verdict" in found.folder_check.violations


# ------------------------------------------------------------ edited inputs
def orders_edit(fn):
    return lambda folder: edit_csv(folder / "orders.csv.gz", fn)


def first_pooled_order(folder) -> int:
    ev = pd.read_csv(folder / "runs" / "mb" / "events.csv.gz")
    return int(ev.loc[(ev["event"] == "assign") & (ev["partner"] >= 0), "order"].iloc[0])


def request_later(folder):
    o = first_pooled_order(folder)
    edit_csv(
        folder / "orders.csv.gz",
        lambda t: t.assign(request_s=np.where(t.index == o, t["request_s"] + 30.0, t["request_s"])),
    )


def patience(value):
    return orders_edit(lambda t: t.assign(patience_s=value))


def origin_moved(t):
    t.loc[7, "origin"] = (t.loc[7, "origin"] + 1) % 144


def solo_edited(t):
    t.loc[3, "solo_m"] += 250.0


def out_of_order(t):
    t.loc[0, "request_s"] = t["request_s"].max() + 1.0


def arc_length(folder):
    edit_npz(folder / "network.npz", lambda z: z["arc_length_m"].__setitem__(0, z["arc_length_m"][0] + 40.0))


def fleet_moved(folder):
    edit_csv(
        folder / "fleet.csv.gz",
        lambda t: t.assign(initial_node=np.where(t["vehicle"] == 2, (t["initial_node"] + 1) % 144, t["initial_node"])),
    )


def param(name, value):
    return lambda folder: edit_meta(folder, lambda m: m["params"].__setitem__(name, value))


def rule(run, name, value):
    return lambda folder: edit_meta(folder, lambda m: m["runs"][run]["rules"].__setitem__(name, value))


EDITED = {
    "a request time": (
        request_later,
        [
            ("inputs-digest", "orders.csv.gz is not the file the run wrote"),
            ("event-log", "request events are not at the order's request time"),
        ],
    ),
    "a longer patience": (patience(500.0), [("inputs-digest", "orders.csv.gz is not the file the run wrote")]),
    "a shorter patience": (
        patience(0.5),
        [("within-patience", "s after its request"), ("inputs-digest", "orders.csv.gz")],
    ),
    "an origin": (
        orders_edit(origin_moved),
        [("orders", "stored solo distances differ from the shortest paths"), ("inputs-digest", "orders.csv.gz")],
    ),
    "a stored solo distance": (orders_edit(solo_edited), [("orders", "stored solo distances differ")]),
    "the request order": (orders_edit(out_of_order), [("orders", "not in request-time order")]),
    "an arc length": (
        arc_length,
        [
            ("movement", "steps' odometer differs from the arc length"),
            ("inputs-digest", "network.npz is not the file the run wrote"),
        ],
    ),
    "an initial vehicle position": (
        fleet_moved,
        [
            ("movement", "vehicle 2 does not start at its initial node"),
            ("inputs-digest", "fleet.csv.gz is not the file the run wrote"),
        ],
    ),
    "D̄ raised to hide a detour": (param("max_detour_m", 1e6), [("inputs-digest", "meta.json's params are not")]),
    "D̄ lowered": (
        param("max_detour_m", 100.0),
        [("max-detour", "m > D̄ = 100 m"), ("inputs-digest", "meta.json's params")],
    ),
    "R̄ lowered": (param("max_pickup_m", 200.0), [("max-pickup", "m > R̄ = 200 m")]),
    "a lower speed": (param("speed_mps", 5.0), [("movement", "arcs driven faster than 5.0000 m/s")]),
    "a higher fare": (
        param("fare_solo_cny_per_km", 6.0),
        [("kpi", "KPI platform_profit_cny: reported"), ("inputs-digest", "meta.json's params")],
    ),
    "a strategy option": (
        lambda f: edit_meta(f, lambda m: m["runs"]["rtv"]["options"].__setitem__("c_ko", 9)),
        [("inputs-digest", "run 'rtv': its options/rules in meta.json are not those of the run")],
    ),
    "an oracle rule relaxed": (
        rule("oracle1", "max_detour_m", 1e6),
        [
            ("oracle-rules", "rule max_detour_m = 1000000.0 is not the folder's parameter"),
            ("inputs-digest", "run 'oracle1'"),
        ],
    ),
    "an oracle flag": (rule("oracle1", "allow_enroute", True), [("inputs-digest", "run 'oracle1'")]),
    "the bound's window": (rule("oracle1", "window", "bound"), [("oracle-rules", "the upper bound's rules are fixed")]),
    "an unknown order rule": (rule("oracle2", "order_rule", "cheapest"), [("oracle-rules", "unknown order rule")]),
    "the bound's status": (
        lambda f: edit_meta(f, lambda m: m["runs"]["bound"].__setitem__("status", "time_limit")),
        [("inputs-digest", "run 'bound'")],
    ),
}


@pytest.mark.parametrize("case", list(EDITED))
def test_an_edited_input_fails_by_name(folder, case):
    """An edited input fails the digest and, where it shows, the check it breaks."""
    tamper, expected = EDITED[case]
    tamper(folder)
    for check, fragment in expected:
        assert_fails(folder, check, fragment)


# ------------------------------------------------------------------- manifest
def test_a_deleted_run_folder_fails(folder):
    """A run meta.json lists without its runs/ folder fails ``manifest``."""
    shutil.rmtree(folder / "runs" / "rtv")
    assert_fails(folder, "manifest", "run 'rtv' listed in meta.json has no folder runs/rtv/ (deleted?)")


def test_a_deleted_oracle_folder_with_its_kpis_fails(folder):
    """A run deleted with its KPI rows still fails ``manifest``: meta.json lists it."""
    shutil.rmtree(folder / "runs" / "oracle2")
    edit_csv(folder / "kpis.csv", lambda t: t[t["run"] != "oracle2"])
    assert_fails(folder, "manifest", "run 'oracle2' listed in meta.json has no folder")


def test_a_run_erased_from_everything_but_the_digest_fails(folder):
    """A run erased from the folder, kpis.csv, hourly.csv and meta.json still fails the digest of the runs."""
    shutil.rmtree(folder / "runs" / "fl")
    edit_csv(folder / "kpis.csv", lambda t: t[t["run"] != "fl"])
    edit_csv(folder / "hourly.csv", lambda t: t[t["run"] != "fl"])

    def forget(m):
        del m["runs"]["fl"]
        m["manifest"]["runs"].remove("fl")
        m["strategies"].remove("fl")

    edit_meta(folder, forget)
    assert_fails(folder, "inputs-digest", "run 'fl': its options/rules in meta.json are not those of the run")


def test_an_added_run_folder_fails(folder):
    """A runs/ folder meta.json does not list fails ``manifest``."""
    shutil.copytree(folder / "runs" / "mb", folder / "runs" / "mb2")
    assert_fails(folder, "manifest", "runs/mb2/ is not a run meta.json lists")


def test_strategies_that_are_not_the_runs_fail(folder):
    """meta.json's strategies must be its runs."""
    edit_meta(folder, lambda m: m["strategies"].remove("rtv"))
    assert_fails(folder, "manifest", "meta.json's strategies (mb, fl, bound, oracle1, oracle2) are not its runs")


def test_a_malformed_manifest_fails(folder):
    """A manifest that is not {"runs": [...]} fails ``manifest``."""
    edit_meta(folder, lambda m: m.__setitem__("manifest", "everything"))
    assert_fails(folder, "manifest", "meta.json's manifest is malformed")


def test_a_removed_digest_fails(folder):
    """A folder with a manifest but no digest had its digest removed: ``inputs-digest`` fails."""
    edit_meta(folder, lambda m: m.pop("inputs_digest"))
    assert_fails(folder, "inputs-digest", "so the digest was removed")


def test_a_malformed_digest_fails(folder):
    """A digest that is not files, params and runs of sha256 digests fails ``inputs-digest``."""
    edit_meta(folder, lambda m: m.__setitem__("inputs_digest", {"files": "x"}))
    assert_fails(folder, "inputs-digest", "inputs_digest is malformed")
