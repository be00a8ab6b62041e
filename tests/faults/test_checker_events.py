"""Event logs edited — times, vehicles, nodes, orders, partners, kinds — each fails a named check."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_fails,
    assert_passes,
    edit_events,
    events,
    first_row,
    joined_pair,
)

base, folder = helpers.base, helpers.folder  # fixtures (clean folders built once per module)


def shift(kind: str, seconds: float, run: str = "mb", nth: int = 0):
    def fn(ev):
        k = ev.index[ev["event"] == kind][nth]
        ev.loc[k, "t_s"] += seconds

    return run, fn


def set_cell(kind: str, column: str, value, run: str = "mb", pooled: bool = False):
    def fn(ev):
        sel = ev["event"] == kind
        if pooled:
            sel &= ev["partner"] >= 0
        ev[column] = ev[column].astype(object)
        ev.loc[ev.index[sel][0], column] = value(ev.loc[ev.index[sel][0]]) if callable(value) else value

    return run, fn


def served_solo_order(ev: pd.DataFrame) -> int:
    """An order served alone (nobody names it as a partner, it names nobody)."""
    named = set(ev.loc[ev["partner"] >= 0, "partner"]) | set(ev.loc[ev["partner"] >= 0, "order"])
    done = ev[(ev["event"] == "dropoff") & ~ev["order"].isin(named)]
    return int(done["order"].iloc[0])


CASES = {
    "pick-up time moved": (shift("pickup", 7.0), "service", "is not at the origin/destination node"),
    "drop-off time moved": (shift("dropoff", -30.0, run="rtv"), "service", "is not at the origin/destination node"),
    "assignment after the patience": (shift("assign", 400.0), "within-patience", "s after its request"),
    "assignment before the request": (
        set_cell("assign", "t_s", lambda r: r["t_s"] - 3600.0),
        "within-patience",
        "s after its request",
    ),
    "assigned vehicle changed": (
        set_cell("assign", "vehicle", lambda r: (r["vehicle"] + 1) % 25, run="fl"),
        "service",
        "served by another vehicle than the one assigned",
    ),
    "pick-up vehicle changed": (
        set_cell("pickup", "vehicle", lambda r: (r["vehicle"] + 3) % 25),
        "service",
        "served by another vehicle than the one assigned",
    ),
    "pick-up node changed": (
        set_cell("pickup", "node", lambda r: (r["node"] + 1) % 144),
        "event-log",
        "pickup events are not at the order's origin",
    ),
    "drop-off node changed": (
        set_cell("dropoff", "node", lambda r: (r["node"] + 1) % 144, run="rtv"),
        "event-log",
        "dropoff events are not at the order's destination",
    ),
    "cancellation node changed": (
        set_cell("cancel", "node", lambda r: (r["node"] + 1) % 144),
        "event-log",
        "cancel events are not at the order's origin",
    ),
    "request time changed": (
        set_cell("request", "t_s", lambda r: r["t_s"] + 60.0),
        "event-log",
        "request events are not at the order's request time",
    ),
    "order id out of range": (set_cell("pickup", "order", 100_000), "event-log", "an order outside 0..99"),
    "negative order id": (set_cell("dropoff", "order", -3), "event-log", "an order outside 0..99"),
    "unknown vehicle id": (set_cell("dropoff", "vehicle", 999, run="fl"), "event-log", "a vehicle outside 0..24"),
    "vehicle on a request": (set_cell("request", "vehicle", 2), "event-log", "a vehicle (a request or cancellation"),
    "unknown event kind": (set_cell("pickup", "event", "teleport"), "event-log", "an unknown event kind"),
    "node outside the network": (set_cell("request", "node", 10**6), "event-log", "a node outside the network"),
    "time that is not a number": (set_cell("dropoff", "t_s", np.nan), "event-log", "a time that is not finite"),
    "infinite time": (set_cell("pickup", "t_s", np.inf, run="rtv"), "event-log", "a time that is not finite"),
    "partner on a pick-up": (set_cell("pickup", "partner", 4), "event-log", "a partner that is not another order"),
    "an order its own partner": (
        set_cell("assign", "partner", lambda r: r["order"], pooled=True),
        "event-log",
        "a partner that is not another order",
    ),
    "pair forgotten": (set_cell("assign", "partner", -1, pooled=True), "kpi", "KPI pooled_passengers: reported"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_an_edited_event_fails_by_name(folder, case):
    (run, fn), check, fragment = CASES[case]
    edit_events(folder, run, fn)
    assert_fails(folder, check, fragment, run=run)


def test_a_partner_on_another_vehicle_fails_capacity(folder):
    joining, _, row = joined_pair(folder)
    ev = events(folder, "mb")
    solo = served_solo_order(ev[ev["vehicle"] != row["vehicle"]].pipe(lambda e: ev[ev["order"].isin(e["order"])]))
    edit_events(
        folder,
        "mb",
        lambda e: e.assign(partner=np.where((e["event"] == "assign") & (e["order"] == joining), solo, e["partner"])),
    )
    assert_fails(folder, "capacity", f"order {joining} is paired with order {solo} of another vehicle", run="mb")


def test_a_partner_already_in_another_pair_fails(folder):
    ev = events(folder, "mb")
    joins = ev[(ev["event"] == "assign") & (ev["partner"] >= 0)]
    first, second = joins.iloc[0], joins.iloc[1]
    edit_events(
        folder, "mb", lambda e: e.assign(partner=np.where(e.index == first.name, second["partner"], e["partner"]))
    )
    assert_fails(folder, "event-log", "named in another pair too", run="mb")


def test_a_duplicated_assignment_fails(folder):
    edit_events(folder, "rtv", lambda ev: pd.concat([ev, ev[ev["event"] == "assign"].head(1)]))
    assert_fails(folder, "assigned-once", "has 2 assign events", run="rtv")


def test_an_assigned_order_also_cancelled_fails(folder):
    def add(ev):
        row = ev[ev["event"] == "request"].iloc[[0]].assign(event="cancel")
        return pd.concat([ev, row])

    edit_events(folder, "mb", add)
    assert_fails(folder, "assigned-once", "is both assigned and cancelled", run="mb")


def test_a_cancellation_before_the_patience_ran_out_fails(folder):
    edit_events(folder, "mb", shift("cancel", -20.0)[1])
    assert_fails(folder, "assigned-once", "not at request + patience", run="mb")


def test_a_deleted_drop_off_fails(folder):
    edit_events(folder, "fl", lambda ev: ev.drop(index=ev.index[ev["event"] == "dropoff"][2]))
    assert_fails(folder, "service", "assigned but never picked up and dropped off", run="fl")


def test_a_deleted_assignment_fails(folder):
    edit_events(folder, "mb", lambda ev: ev.drop(index=ev.index[(ev["event"] == "assign") & (ev["partner"] < 0)][0]))
    assert_fails(folder, "service", "picked up or dropped off but never assigned", run="mb")


def test_a_deleted_request_fails(folder):
    edit_events(folder, "mb", lambda ev: ev.drop(index=ev.index[ev["event"] == "request"][5]))
    assert_fails(folder, "event-log", "orders do not have exactly one request event", run="mb")


def test_a_pick_up_before_the_assignment_fails(folder):
    def early(ev):
        order = int(ev.loc[first_row(ev, event="pickup"), "order"])
        assign_t = ev.loc[(ev["event"] == "assign") & (ev["order"] == order), "t_s"].iloc[0]
        ev.loc[(ev["event"] == "pickup") & (ev["order"] == order), "t_s"] = assign_t - 5.0

    edit_events(folder, "mb", early)
    assert_fails(folder, "service", "pick-up before assignment or drop-off before pick-up", run="mb")


def test_a_third_passenger_in_a_pooled_vehicle_fails_capacity(folder):
    """Move a solo passenger, served while a pair rides, into the pair's vehicle."""
    ev = events(folder, "mb")
    joining, first, row = joined_pair(folder)
    pair = ev[ev["order"].isin([joining, first])]
    start, end = pair["t_s"][pair["event"] == "assign"].min(), pair["t_s"][pair["event"] == "dropoff"].max()
    named = set(ev.loc[ev["partner"] >= 0, "partner"]) | set(ev.loc[ev["partner"] >= 0, "order"])
    solo = ev[
        (ev["event"] == "assign")
        & ~ev["order"].isin(named)
        & (ev["vehicle"] != row["vehicle"])
        & (ev["t_s"] > start)
        & (ev["t_s"] < end)
    ]
    other = int(solo["order"].iloc[0])
    edit_events(
        folder,
        "mb",
        lambda e: e.assign(
            vehicle=np.where(
                (e["order"] == other) & e["event"].isin(["assign", "pickup", "dropoff"]), row["vehicle"], e["vehicle"]
            )
        ),
    )
    assert_fails(folder, "capacity", "passengers assigned or on board at once", run="mb")


def test_a_reordered_event_log_still_passes(folder):
    """The row order of the log carries no meaning: shuffling it changes nothing."""
    edit_events(folder, "rtv", lambda ev: ev.sample(frac=1.0, random_state=1))
    assert_passes(folder)
