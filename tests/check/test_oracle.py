"""Oracle and bound pairs edited: each pair's window, feasibility, service and pick-up order, saving, route
length, detours, shared and pick-up distances are recomputed from the orders and the folder's network —
en-route pairs included — so a forged pair fails ``oracle-pairs`` (and the KPIs built on it ``kpi``); the pair
rules recorded for an oracle are the folder's parameters (``oracle-rules``)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from check.tamper import (
    assert_fails,
    copy,
    edit_csv,
    edit_meta,
    run_violations,
    set_kpi,
    violations,
)


def pairs_path(folder, run):
    return folder / "runs" / run / "pairs.csv.gz"


def edit_pairs(folder, run, fn):
    edit_csv(pairs_path(folder, run), fn)


def add_to(column, amount, row=0):
    def fn(t):
        t.loc[row, column] += amount

    return fn


def unpaired_order(folder, run, after_s: float, before_s: float = np.inf) -> tuple[int, float]:
    """(id, request time) of an order in no pair of the run, requested in [after_s, before_s)."""
    orders = pd.read_csv(folder / "orders.csv.gz")
    pairs = pd.read_csv(pairs_path(folder, run))
    free = orders[
        ~orders["order_id"].isin(pairs["first_id"])
        & ~orders["order_id"].isin(pairs["second_id"])
        & (orders["request_s"] >= after_s)
        & (orders["request_s"] < before_s)
    ]
    return int(free["order_id"].iloc[0]), float(free["request_s"].iloc[0])


def rejoin(folder, run, row, partner, t):
    """Pair the first order of ``row`` with ``partner`` instead."""

    def fn(p):
        p.loc[row, "second_id"] = partner
        p.loc[row, "second_request_s"] = t

    edit_pairs(folder, run, fn)


STORED = {
    "saving_m": 100.0,
    "length_m": -100.0,
    "detour_first_m": 50.0,
    "detour_second_m": 50.0,
    "shared_m": 75.0,
    "pickup_m": 10.0,
}


@pytest.mark.parametrize("run", ["oracle1", "oracle2", "bound"])
@pytest.mark.parametrize("column", list(STORED))
def test_every_stored_pair_figure_edited_fails(folder, run, column):
    """Every figure pairs.csv.gz stores is recomputed: any one edited fails ``oracle-pairs``."""
    edit_pairs(folder, run, add_to(column, STORED[column]))
    fragment = (
        "stored weights differ from the largest realisable savings"
        if (run, column) == ("bound", "saving_m")
        else f"pairs' stored {column} differ from the recomputed ones"
    )
    assert_fails(folder, "oracle-pairs", fragment, run=run)


@pytest.mark.parametrize("column", ["saving_m", "detour_first_m", "shared_m"])
def test_an_en_route_pairs_figures_are_recomputed_too(enroute, tmp_path, column):
    """An en-route pair's figures are recomputed from the node where the vehicle turns towards the second order."""
    folder = copy(enroute, tmp_path)
    pairs = pd.read_csv(pairs_path(folder, "oracle1"))
    row = int(np.flatnonzero(pairs["enroute"].to_numpy())[0])
    edit_pairs(folder, "oracle1", add_to(column, 100.0, row))
    assert_fails(folder, "oracle-pairs", f"pairs' stored {column} differ", run="oracle1")


def test_an_impossible_en_route_pair_with_a_forged_saving_fails(enroute, tmp_path):
    """Requests 58 min apart, a 100 km saving, flagged en route, the KPI total raised to match: the second
    order requests long after the first one was delivered, and the saving is not the route's."""
    folder = copy(enroute, tmp_path)
    pairs = pd.read_csv(pairs_path(folder, "oracle1"))
    row = int(np.flatnonzero(pairs["enroute"].to_numpy())[0])
    t0 = float(pairs.loc[row, "first_request_s"])
    late, t = unpaired_order(folder, "oracle1", t0 + 57 * 60, t0 + 59 * 60)
    rejoin(folder, "oracle1", row, late, t)
    edit_pairs(folder, "oracle1", add_to("saving_m", 100_000.0, row))
    set_kpi(folder, "oracle1", "total_saving_km", lambda v: v + 100.0)
    found = assert_fails(folder, "oracle-pairs", "are en-route pairs outside the en-route window", run="oracle1")
    assert any("stored saving_m differ" in m for m in found["oracle-pairs"])
    assert any("KPI total_saving_km: reported" in m for m in found["kpi"])


def test_a_waiting_pair_further_apart_than_the_planner_patience_fails(folder):
    """A waiting pair's requests lie within K̄ of each other."""
    pairs = pd.read_csv(pairs_path(folder, "oracle1"))
    late, t = unpaired_order(folder, "oracle1", float(pairs.loc[0, "first_request_s"]) + 600.0)
    rejoin(folder, "oracle1", 0, late, t)
    assert_fails(folder, "oracle-pairs", "of waiting orders request more than K̄ = 90 s apart", run="oracle1")


def test_an_en_route_pair_relabelled_waiting_fails(enroute, tmp_path):
    """An en-route pair relabelled waiting is held to the waiting window, and fails it."""
    folder = copy(enroute, tmp_path)
    edit_pairs(folder, "oracle2", lambda p: p.assign(enroute=False))
    assert_fails(folder, "oracle-pairs", "of waiting orders request more than K̄", run="oracle2")


def test_en_route_pairs_in_an_oracle_that_does_not_allow_them_fail(enroute, tmp_path):
    """En-route pairs only where the oracle's rules allow them."""
    folder = copy(enroute, tmp_path)
    edit_meta(folder, lambda m: m["runs"]["oracle1"]["rules"].__setitem__("allow_enroute", False))
    assert_fails(folder, "oracle-pairs", "en-route pairs in an oracle whose rules do not allow them", run="oracle1")


def test_pairs_beyond_a_lowered_pickup_radius_fail(enroute, tmp_path):
    """oracle2 tests the pick-up distance (pickup_check): with R̄ lowered, its pairs are infeasible."""
    folder = copy(enroute, tmp_path)

    def lower(m):
        m["params"]["max_pickup_m"] = 100.0
        m["runs"]["oracle2"]["rules"]["max_pickup_m"] = 100.0

    edit_meta(folder, lower)
    assert_fails(folder, "oracle-pairs", "are not feasible under the rules", run="oracle2")


def test_the_later_order_picked_up_first_fails_where_the_rules_forbid_it(folder):
    """Without both pick-up orders in the rules, the earlier request is picked up first."""

    def swap(p):
        k = int(np.flatnonzero((p["second_request_s"] > p["first_request_s"]).to_numpy())[0])
        p.loc[k, ["first_id", "second_id"]] = p.loc[k, ["second_id", "first_id"]].to_numpy()
        p.loc[k, ["first_request_s", "second_request_s"]] = p.loc[k, ["second_request_s", "first_request_s"]].to_numpy()

    edit_pairs(folder, "oracle1", swap)
    assert_fails(folder, "oracle-pairs", "pick the later order up first, which the rules do not allow", run="oracle1")


def test_a_flipped_service_order_fails(folder):
    """The stored figures are those of the stored service order: a flipped one no longer matches them."""
    edit_pairs(
        folder,
        "oracle2",
        lambda p: p.assign(
            service_order=np.where(
                p.index == 0, np.where(p["service_order"] == "FOFO", "FOLO", "FOFO"), p["service_order"]
            )
        ),
    )
    assert_fails(folder, "oracle-pairs", "differ from the recomputed ones", run="oracle2")


def test_an_unknown_service_order_fails(folder):
    """The service order is FOFO or FOLO."""
    edit_pairs(folder, "oracle1", lambda p: p.assign(service_order="LIFO"))
    assert_fails(folder, "oracle-pairs", "have a service order other than FOFO/FOLO", run="oracle1")


def test_an_order_in_two_pairs_fails(folder):
    """The pairs are a matching: no order in two pairs."""

    def dup(p):
        p.loc[1, "first_id"] = p.loc[0, "first_id"]

    edit_pairs(folder, "oracle1", dup)
    assert_fails(folder, "oracle-pairs", "appears in 2 pairs", run="oracle1")


def test_a_duplicated_pair_row_fails(folder):
    """A pair stored twice puts its orders in two pairs."""
    edit_pairs(folder, "oracle2", lambda p: pd.concat([p, p.iloc[[2]]]))
    assert_fails(folder, "oracle-pairs", "appears in 2 pairs", run="oracle2")


def test_a_pair_of_an_unknown_order_fails(folder):
    """Pairs name orders of orders.csv.gz."""
    edit_pairs(folder, "oracle1", add_to("second_id", 10**6))
    assert_fails(folder, "oracle-pairs", "pairs name order ids that are not in orders.csv.gz", run="oracle1")


def test_an_order_paired_with_itself_fails(folder):
    """A pair is two different orders."""

    def same(p):
        p.loc[0, "second_id"] = p.loc[0, "first_id"]

    edit_pairs(folder, "oracle1", same)
    assert_fails(folder, "oracle-pairs", "pair an order with itself", run="oracle1")


def test_a_stored_request_time_edited_fails(folder):
    """A pair's stored request times are its orders'."""
    edit_pairs(folder, "oracle2", add_to("first_request_s", 30.0))
    assert_fails(folder, "oracle-pairs", "stored first_request_s differ from orders.csv.gz", run="oracle2")


def test_a_deleted_pair_fails_the_kpis(folder):
    """The oracle's KPIs are recomputed from its pairs: a deleted pair fails ``kpi``."""
    edit_pairs(folder, "oracle1", lambda p: p.iloc[1:])
    assert_fails(folder, "kpi", "KPI pairs: reported 23.0, recomputed 22", run="oracle1")


def test_a_bound_pair_that_no_run_could_form_fails(folder):
    """The bound's pairs are edges of its graph: orders requested too far apart are none."""
    pairs = pd.read_csv(pairs_path(folder, "bound"))
    late, t = unpaired_order(folder, "bound", float(pairs.loc[0, "first_request_s"]) + 1500.0)
    rejoin(folder, "bound", 0, late, t)
    assert_fails(folder, "oracle-pairs", "are not edges of the upper bound's graph", run="bound")


def test_a_relaxed_threshold_is_caught_by_the_digest_and_the_oracle_rules(folder):
    """Raising D̄ in meta.json hides nothing: the digest pins the run's parameters, and the oracles' rules
    (and the service orders they chose) no longer match them."""
    edit_meta(folder, lambda m: m["params"].__setitem__("max_detour_m", 1e6))
    found = violations(folder)
    assert set(found) == {"inputs-digest", "oracle-rules", "oracle-pairs"}
    assert any("not served in the order the rule min_feasible picks" in m for m in found["oracle-pairs"])


# ------------------------------------------------------------------- manifest


def test_oracle_pair_tampering_is_caught(clean_copy):
    """An order in two pairs of an oracle fails ``oracle-pairs``."""
    path = clean_copy / "runs" / "oracle1" / "pairs.csv.gz"
    pairs = pd.read_csv(path)
    pairs.loc[1, "first_id"] = pairs.loc[0, "first_id"]  # one order in two pairs
    pairs.to_csv(path, index=False)
    assert "oracle-pairs" in run_violations(clean_copy)
