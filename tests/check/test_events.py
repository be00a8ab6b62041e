"""A simulation run's event log and trajectories edited — times, vehicles, nodes, orders, partners, kinds,
odometers, offsets — each fails a named check (``event-log``, ``assigned-once``, ``within-patience``,
``service``, ``max-pickup``, ``max-detour``, ``capacity``, ``movement``)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from check.tamper import (
    assert_fails,
    assert_passes,
    edit_events,
    edit_npz,
    events,
    first_row,
    joined_pair,
    run_violations,
)
from rpbench.cli import main


# ---------------------------------------------------------------- event log
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
    """Each edit of an event fails the check of the rule it breaks, for the run it was made in."""
    (run, fn), check, fragment = CASES[case]
    edit_events(folder, run, fn)
    assert_fails(folder, check, fragment, run=run)


def test_a_partner_on_another_vehicle_fails_capacity(folder):
    """Partners ride one vehicle: a partner assigned to another vehicle fails ``capacity``."""
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
    """No order is in two pairs: naming a partner of another pair fails ``event-log``."""
    ev = events(folder, "mb")
    joins = ev[(ev["event"] == "assign") & (ev["partner"] >= 0)]
    first, second = joins.iloc[0], joins.iloc[1]
    edit_events(
        folder, "mb", lambda e: e.assign(partner=np.where(e.index == first.name, second["partner"], e["partner"]))
    )
    assert_fails(folder, "event-log", "named in another pair too", run="mb")


def test_a_duplicated_assignment_fails(folder):
    """An order is assigned at most once."""
    edit_events(folder, "rtv", lambda ev: pd.concat([ev, ev[ev["event"] == "assign"].head(1)]))
    assert_fails(folder, "assigned-once", "has 2 assign events", run="rtv")


def test_an_assigned_order_also_cancelled_fails(folder):
    """An assigned order is never also cancelled."""

    def add(ev):
        row = ev[ev["event"] == "request"].iloc[[0]].assign(event="cancel")
        return pd.concat([ev, row])

    edit_events(folder, "mb", add)
    assert_fails(folder, "assigned-once", "is both assigned and cancelled", run="mb")


def test_a_cancellation_before_the_patience_ran_out_fails(folder):
    """A cancellation happens exactly at request + patience."""
    edit_events(folder, "mb", shift("cancel", -20.0)[1])
    assert_fails(folder, "assigned-once", "not at request + patience", run="mb")


def test_a_deleted_drop_off_fails(folder):
    """Every assigned passenger is picked up and dropped off."""
    edit_events(folder, "fl", lambda ev: ev.drop(index=ev.index[ev["event"] == "dropoff"][2]))
    assert_fails(folder, "service", "assigned but never picked up and dropped off", run="fl")


def test_a_deleted_assignment_fails(folder):
    """A passenger picked up or dropped off was assigned first."""
    edit_events(folder, "mb", lambda ev: ev.drop(index=ev.index[(ev["event"] == "assign") & (ev["partner"] < 0)][0]))
    assert_fails(folder, "service", "picked up or dropped off but never assigned", run="mb")


def test_a_deleted_request_fails(folder):
    """Every order has exactly one request event."""
    edit_events(folder, "mb", lambda ev: ev.drop(index=ev.index[ev["event"] == "request"][5]))
    assert_fails(folder, "event-log", "orders do not have exactly one request event", run="mb")


def test_a_pick_up_before_the_assignment_fails(folder):
    """Pick-up follows assignment, drop-off follows pick-up."""

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


# ---------------------------------------------------------------- movement
def traj_path(folder, run="mb"):
    return folder / "runs" / run / "trajectories.npz"


def middle_of_vehicle(z, v=3):
    lo, hi = z["vehicle_offsets"][v], z["vehicle_offsets"][v + 1]
    return int(lo + (hi - lo) // 2), int(hi)


def bump_odometer(z):
    k, _ = middle_of_vehicle(z)
    z["odo_m"][k] += 50.0


def shift_rest_of_odometer(z):
    k, hi = middle_of_vehicle(z)
    z["odo_m"][k:hi] += 100.0


def arrive_early(z):
    z["t_s"][5:] -= 3.0  # arrive at entry 5 three seconds too early


def time_backwards(z):
    k, _ = middle_of_vehicle(z)
    z["t_s"][k] = z["t_s"][k - 1] - 10.0


def leap_to_a_far_node(z):
    k, _ = middle_of_vehicle(z)
    z["node"][k] = (z["node"][k] + 70) % 144  # across the 12x12 grid: no arc leads there


def node_outside(z):
    k, _ = middle_of_vehicle(z)
    z["node"][k] = 10**6


def nan_at(key):
    def fn(z):
        k, _ = middle_of_vehicle(z, 5)
        z[key][k] = np.nan

    return fn


def inf_time(z):
    z["t_s"][-1] = np.inf


def broken_offsets(z):
    z["vehicle_offsets"][3] = z["vehicle_offsets"][2]


def vehicle_missing(z):
    z["vehicle_offsets"] = z["vehicle_offsets"][:-1].copy()
    z["vehicle_offsets"][-1] = len(z["node"])


def wrong_start(z):
    z["node"][z["vehicle_offsets"][4]] = (z["node"][z["vehicle_offsets"][4]] + 1) % 144


MOVES = {
    "an odometer reading raised": (bump_odometer, "steps' odometer differs from the arc length"),
    "the odometer shifted from one entry on": (shift_rest_of_odometer, "steps' odometer differs from the arc length"),
    "arriving early (teleport)": (arrive_early, "arcs driven faster than"),
    "time running backwards": (time_backwards, "time runs backwards in trajectory entry"),
    "a leap to a far node": (leap_to_a_far_node, "steps are not network arcs"),
    "a node outside the network": (node_outside, "name a node outside the network"),
    "a NaN odometer": (nan_at("odo_m"), "have a non-finite time or odometer (NaN or inf)"),
    "a NaN time": (nan_at("t_s"), "have a non-finite time or odometer (NaN or inf)"),
    "an infinite time": (inf_time, "have a non-finite time or odometer (NaN or inf)"),
    "offsets that leave a vehicle without a trajectory": (broken_offsets, "do not split the entries"),
    "one trajectory too few": (vehicle_missing, "24 trajectories for 25 vehicles"),
    "a vehicle starting elsewhere": (wrong_start, "vehicle 4 does not start at its initial node"),
}


@pytest.mark.parametrize("case", list(MOVES))
def test_an_edited_trajectory_fails_movement(folder, case):
    """Vehicles drive network arcs from their initial node, odometer = arc lengths, no faster than the speed."""
    fn, fragment = MOVES[case]
    edit_npz(traj_path(folder), fn)
    assert_fails(folder, "movement", fragment, run="mb")


# ------------------------------------------------- a small clean folder
def test_pickup_time_tampering_is_caught(clean_copy, capsys):
    """A pick-up time moved off the vehicle's trajectory fails ``service``, and ``rpbench check`` exits 1."""

    def shift(ev):
        i = ev.index[ev["event"] == "pickup"][0]
        ev.loc[i, "t_s"] += 7.0
        return ev

    edit_events(clean_copy, "mb", shift)
    assert "service" in run_violations(clean_copy)
    assert main(["check", str(clean_copy)]) == 1
    assert "[service]" in capsys.readouterr().out


def test_double_assignment_is_caught(clean_copy):
    """An order assigned twice fails ``assigned-once``."""
    edit_events(clean_copy, "rtv", lambda ev: pd.concat([ev, ev[ev["event"] == "assign"].head(1)]))
    assert "assigned-once" in run_violations(clean_copy)


def test_thresholds_are_rechecked(clean_copy):
    """D̄ and R̄ are re-applied to the driven distances: lowered, they fail ``max-detour`` and ``max-pickup``."""
    meta = json.loads((clean_copy / "meta.json").read_text())
    meta["params"]["max_detour_m"] = 100.0
    meta["params"]["max_pickup_m"] = 200.0
    (clean_copy / "meta.json").write_text(json.dumps(meta))
    found = run_violations(clean_copy)
    assert "max-detour" in found and "max-pickup" in found


def test_teleporting_vehicle_is_caught(clean_copy):
    """A vehicle arriving earlier than the speed allows fails ``movement``."""
    path = clean_copy / "runs" / "mb" / "trajectories.npz"
    z = dict(np.load(path))
    z["t_s"][5:] -= 3.0  # arrive at node 5 three seconds too early
    np.savez_compressed(path, **z)
    assert "movement" in run_violations(clean_copy)


def test_assignment_after_patience_is_caught(clean_copy):
    """An assignment later than the order's patience fails ``within-patience``."""
    orders = pd.read_csv(clean_copy / "orders.csv.gz")
    orders["patience_s"] = 0.5
    orders.to_csv(clean_copy / "orders.csv.gz", index=False)
    assert "within-patience" in run_violations(clean_copy)


@pytest.mark.parametrize("late_s, fails", [(1e-12, False), (1e-7, False), (1.0, True)])
def test_a_drop_off_in_float_noise_after_the_next_assignment_is_at_the_same_instant(late_s, fails):
    """A pair dropped off at 100 s (plus float noise from summed arc times) hands its vehicle to an order
    assigned in the round at 100 s: the simulator processed the drop-off first; a second later it did not."""
    from rpbench.check.core import RunCheck
    from rpbench.check.events import _check_capacity

    rc = RunCheck("x")
    t_drop = np.array([100.0 + late_s, 100.0 + late_s, 200.0])
    _check_capacity(
        rc,
        vehicle=np.array([0, 0, 0]),
        t_assign=np.array([0.0, 0.0, 100.0]),
        t_pick=np.array([10.0, 20.0, 150.0]),
        t_drop=t_drop,
        served=np.ones(3, bool),
    )
    assert ("capacity" in rc.violations) is fails
