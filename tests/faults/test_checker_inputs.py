"""The inputs a verdict rests on — orders, network, fleet, parameters, run options, the run list — edited or
deleted: the run-time digest and manifest catch what no other check would (a relaxed threshold, a deleted run)."""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_fails,
    edit_csv,
    edit_meta,
    edit_npz,
    violations,
)

base, folder = helpers.base, helpers.folder  # fixtures (clean folders built once per module)


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


CASES = {
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


@pytest.mark.parametrize("case", list(CASES))
def test_an_edited_input_fails_by_name(folder, case):
    tamper, expected = CASES[case]
    tamper(folder)
    for check, fragment in expected:
        assert_fails(folder, check, fragment)


def test_a_relaxed_threshold_is_caught_by_the_digest_and_the_oracle_rules(folder):
    """Raising D̄ in meta.json hides nothing: the digest pins the run's parameters, and the oracles' rules
    (and the service orders they chose) no longer match them."""
    edit_meta(folder, lambda m: m["params"].__setitem__("max_detour_m", 1e6))
    found = violations(folder)
    assert set(found) == {"inputs-digest", "oracle-rules", "oracle-pairs"}
    assert any("not served in the order the rule min_feasible picks" in m for m in found["oracle-pairs"])


# ------------------------------------------------------------------- manifest
def test_a_deleted_run_folder_fails(folder):
    shutil.rmtree(folder / "runs" / "rtv")
    assert_fails(folder, "manifest", "run 'rtv' listed in meta.json has no folder runs/rtv/ (deleted?)")


def test_a_deleted_oracle_folder_with_its_kpis_fails(folder):
    shutil.rmtree(folder / "runs" / "oracle2")
    edit_csv(folder / "kpis.csv", lambda t: t[t["run"] != "oracle2"])
    assert_fails(folder, "manifest", "run 'oracle2' listed in meta.json has no folder")


def test_a_run_erased_from_everything_but_the_digest_fails(folder):
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
    shutil.copytree(folder / "runs" / "mb", folder / "runs" / "mb2")
    assert_fails(folder, "manifest", "runs/mb2/ is not a run meta.json lists")


def test_strategies_that_are_not_the_runs_fail(folder):
    edit_meta(folder, lambda m: m["strategies"].remove("rtv"))
    assert_fails(folder, "manifest", "meta.json's strategies (mb, fl, bound, oracle1, oracle2) are not its runs")


def test_a_malformed_manifest_fails(folder):
    edit_meta(folder, lambda m: m.__setitem__("manifest", "everything"))
    assert_fails(folder, "manifest", "meta.json's manifest is malformed")


def test_a_removed_digest_fails(folder):
    edit_meta(folder, lambda m: m.pop("inputs_digest"))
    assert_fails(folder, "inputs-digest", "so the digest was removed")


def test_a_malformed_digest_fails(folder):
    edit_meta(folder, lambda m: m.__setitem__("inputs_digest", {"files": "x"}))
    assert_fails(folder, "inputs-digest", "inputs_digest is malformed")
