"""The Table 2 KPIs of rpbench.results.metrics on a hand-made event log and trajectories.

Two vehicles driving at 10 m/s, four orders:

* order 0 — solo, vehicle 0: requested 0 s, assigned 10 s, picked up 40 s, dropped 190 s; l = 1500 m.
* orders 1 and 2 — a pooled pair in vehicle 1 (FOFO): order 1 (A, l = 1200 m) requested 10 s, assigned
  30 s (vacant), picked up 60 s, dropped 210 s; order 2 (B, l = 1500 m) requested 20 s, joins A at 50 s
  (assign event partner = 1), picked up 110 s, dropped 260 s.
* order 3 — requested 3700 s (the next hour), never assigned, cancelled at 3790 s; l = 2000 m.

Trajectories (time s -> odometer m)::

    vehicle 0:  0 -> 0,  40 -> 400,  190 -> 1900,  290 -> 2900
    vehicle 1:  0 -> 0,  60 -> 600,  110 -> 1100,  210 -> 2100,  260 -> 2600

Odometers at events (linear in between, e.g. vehicle 0 at 10 s: 100 m; vehicle 1 at 30 s: 300 m, 50 s: 500 m).
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest

from rpbench.results.metrics import (
    BUDGET_KPI,
    EXTRA_KPIS,
    KPI_LABELS,
    KPI_ORDER,
    TIMELINE_STATES,
    TIMING_KPIS,
    _pair_length,
    count_at,
    decision_kpis,
    decision_times,
    hourly,
    kpis,
    mean_count,
    occupied_distance_m,
    odometer_at,
    over_budget,
    passenger_table,
    state_spells,
)
from rpbench.scenarios.base import Params
from rpbench.sim.simulator import EVENT_COLUMNS, EVENT_DTYPES

NAN = float("nan")


def event_log(rows: list[tuple]) -> pd.DataFrame:
    """Rows (t_s, event, order, vehicle, node, kind, partner, fofo) in the simulator's format and order."""
    full = [(t, ev, o, v, node, kind, NAN, NAN, partner, fofo) for t, ev, o, v, node, kind, partner, fofo in rows]
    return (
        pd.DataFrame(full, columns=EVENT_COLUMNS)
        .astype(EVENT_DTYPES)
        .sort_values(["t_s", "order", "event"], kind="stable")
        .reset_index(drop=True)
    )


def trajectories(per_vehicle: list[list[tuple[int, float, float]]]) -> dict[str, np.ndarray]:
    """The simulator's trajectory dict from per-vehicle lists of (node, t_s, odo_m)."""
    offsets = np.concatenate([[0], np.cumsum([len(v) for v in per_vehicle])]).astype(np.int64)
    flat = [p for v in per_vehicle for p in v]
    return {
        "vehicle_offsets": offsets,
        "node": np.array([p[0] for p in flat], np.int32),
        "t_s": np.array([p[1] for p in flat], float),
        "odo_m": np.array([p[2] for p in flat], float),
    }


EVENTS = event_log(
    [
        # t_s    event       order veh node  kind     partner fofo
        (0.0, "request", 0, -1, 10, "", -1, False),
        (10.0, "request", 1, -1, 20, "", -1, False),
        (10.0, "assign", 0, 0, -1, "vacant", -1, False),
        (20.0, "request", 2, -1, 21, "", -1, False),
        (30.0, "assign", 1, 1, -1, "vacant", -1, False),
        (40.0, "pickup", 0, 0, 10, "", -1, False),
        (50.0, "assign", 2, 1, -1, "join", 1, True),
        (60.0, "pickup", 1, 1, 20, "", -1, False),
        (110.0, "pickup", 2, 1, 21, "", -1, False),
        (190.0, "dropoff", 0, 0, 11, "", -1, False),
        (200.0, "reposition", -1, 0, 12, "", -1, False),  # not a passenger event: ignored
        (210.0, "dropoff", 1, 1, 22, "", -1, False),
        (260.0, "dropoff", 2, 1, 23, "", -1, False),
        (3700.0, "request", 3, -1, 30, "", -1, False),
        (3790.0, "cancel", 3, -1, 30, "", -1, False),
    ]
)
TRAJ = trajectories(
    [
        [(1, 0.0, 0.0), (10, 40.0, 400.0), (11, 190.0, 1900.0), (12, 290.0, 2900.0)],
        [(2, 0.0, 0.0), (20, 60.0, 600.0), (21, 110.0, 1100.0), (22, 210.0, 2100.0), (23, 260.0, 2600.0)],
    ]
)
SOLO_M = np.array([1500.0, 1200.0, 1500.0, 2000.0])
REQUEST_S = np.array([0.0, 10.0, 20.0, 3700.0])


@pytest.fixture(scope="module")
def tab() -> pd.DataFrame:
    return passenger_table(EVENTS, SOLO_M, REQUEST_S, TRAJ)


@pytest.fixture(scope="module")
def kpi(tab) -> dict[str, float]:
    return kpis(tab, occupied_distance_m(EVENTS, TRAJ), Params())


def test_odometer_at():
    # vehicle 0 at 10 s: 400 · 10/40 = 100; at 115 s: 400 + (115 - 40)·10 = 1150; past the end: 2900 (held).
    # vehicle 1 at 50 s: 500; vehicle -1 (unassigned): NaN.
    out = odometer_at(TRAJ, np.array([0, 0, 0, 1, -1]), np.array([10.0, 115.0, 5000.0, 50.0, 30.0]))
    assert out[:4] == pytest.approx([100.0, 1150.0, 2900.0, 500.0])
    assert np.isnan(out[4])


def test_passenger_table_times_and_links(tab):
    assert tab["request_s"].tolist() == [0.0, 10.0, 20.0, 3700.0]
    assert tab["assign_s"].tolist()[:3] == [10.0, 30.0, 50.0] and np.isnan(tab["assign_s"][3])
    assert tab["pickup_s"].tolist()[:3] == [40.0, 60.0, 110.0] and np.isnan(tab["pickup_s"][3])
    assert tab["dropoff_s"].tolist()[:3] == [190.0, 210.0, 260.0] and np.isnan(tab["dropoff_s"][3])
    assert np.isnan(tab["cancel_s"][:3]).all() and tab["cancel_s"][3] == 3790.0
    assert tab["vehicle"].tolist() == [0, 1, 1, -1]
    # Only B's join carries partner = 1; A learns its partner (2) from it.
    assert tab["partner"].tolist() == [-1, 2, 1, -1]
    assert tab["kind"].tolist() == ["vacant", "vacant", "join", ""]
    assert tab["served"].tolist() == [True, True, True, False]
    assert tab["pooled"].tolist() == [False, True, True, False]


def test_passenger_table_distances(tab):
    # ride = odometer at drop-off - at pick-up:
    #   order 0: 1900 - 400 = 1500;  A: 2100 - 600 = 1500;  B: 2600 - 1100 = 1500
    # detour = ride - solo: 1500 - 1500 = 0;  1500 - 1200 = 300;  1500 - 1500 = 0
    served = tab.iloc[:3]
    assert served["ride_m"].to_numpy() == pytest.approx([1500.0, 1500.0, 1500.0])
    assert served["detour_m"].to_numpy() == pytest.approx([0.0, 300.0, 0.0])
    # pick-up distance:
    #   order 0 from its assignment: odo(40 s) 400 - odo(10 s) 100 = 300
    #   A from its assignment:       odo(60 s) 600 - odo(30 s) 300 = 300
    #   B after A's pick-up (A was collected first, at 60 s > B's assignment at 50 s): 1100 - 600 = 500
    assert served["pickup_m"].to_numpy() == pytest.approx([300.0, 300.0, 500.0])
    # shared: both on board from B's pick-up (110 s, 1100 m) to A's drop-off (210 s, 2100 m) = 1000
    assert np.isnan(tab["shared_m"][0]) and np.isnan(tab["shared_m"][3])
    assert tab["shared_m"][1:3].to_numpy() == pytest.approx([1000.0, 1000.0])
    assert np.isnan(tab["ride_m"][3])  # the cancelled order rode nothing


def test_pair_length(tab):
    # L = ride_A + ride_B - shared = 1500 + 1500 - 1000 = 2000 = odo at B's drop-off 2600 - at A's pick-up 600.
    assert _pair_length(tab, np.array([0, 2, 1, 0]))[1:3] == pytest.approx([2000.0, 2000.0])


def test_occupied_distance(tab):
    # vehicle 0: occupied from 40 s (400 m) to 190 s (1900 m) = 1500; the empty drive to 2900 m does not count.
    # vehicle 1: occupied from A's pick-up (600 m) to B's drop-off (2600 m) = 2000.
    assert occupied_distance_m(EVENTS, TRAJ) == pytest.approx([1500.0, 2000.0])


def test_occupied_distance_skips_empty_legs():
    # One vehicle, two solo trips: X rides 0 -> 1000 m, the vehicle drives empty to 1500 m, Y rides 1500 -> 2500 m.
    # Occupied = 1000 + 1000 = 2000 (not 2500).  A second vehicle with no passengers drives 0 m occupied.
    events = event_log(
        [
            (0.0, "pickup", 0, 0, 1, "", -1, False),
            (100.0, "dropoff", 0, 0, 2, "", -1, False),
            (150.0, "pickup", 1, 0, 3, "", -1, False),
            (250.0, "dropoff", 1, 0, 4, "", -1, False),
        ]
    )
    traj = trajectories([[(1, 0.0, 0.0), (4, 250.0, 2500.0)], [(5, 0.0, 0.0), (6, 300.0, 3000.0)]])
    assert occupied_distance_m(events, traj) == pytest.approx([2000.0, 0.0])
    # No pick-ups or drop-offs at all: zeros.
    assert occupied_distance_m(events.iloc[:0], traj).tolist() == [0.0, 0.0]


def test_counts_and_ratios(kpi):
    assert set(KPI_ORDER + EXTRA_KPIS) == set(kpi)
    assert (kpi["orders"], kpi["served"], kpi["cancelled"], kpi["pooled_passengers"], kpi["pairs"]) == (4, 3, 1, 2, 1)
    assert kpi["response_rate"] == pytest.approx(3 / 4)  # served 3 of 4 orders
    assert kpi["pairing_ratio"] == pytest.approx(2 / 3)  # 2 pooled of 3 served
    assert kpi["pairing_ratio_of_orders"] == pytest.approx(2 / 4)  # 2 pooled of 4 orders


def test_times(kpi):
    # response = assign - request over served: (10 - 0) + (30 - 10) + (50 - 20) = 10 + 20 + 30 -> mean 20
    assert kpi["avg_response_time_s"] == pytest.approx(20.0)
    # pick-up time = pickup - assign: (40 - 10) + (60 - 30) + (110 - 50) = 30 + 30 + 60 -> mean 40
    assert kpi["avg_pickup_time_s"] == pytest.approx(40.0)
    # pick-up distance: (300 + 300 + 500) / 3
    assert kpi["avg_pickup_distance_m"] == pytest.approx(1100.0 / 3)


def test_distances(kpi):
    assert kpi["avg_detour_m"] == pytest.approx(150.0)  # pooled: (300 + 0) / 2
    assert kpi["avg_shared_m"] == pytest.approx(1000.0)  # pooled: (1000 + 1000) / 2
    assert kpi["total_occupied_km"] == pytest.approx(3.5)  # 1500 + 2000 m
    assert kpi["total_solo_served_km"] == pytest.approx(4.2)  # 1500 + 1200 + 1500 m (not the cancelled 2000)
    # saving = 4.2 - 3.5 = 0.7 km = the pair's l_A + l_B - L = 1200 + 1500 - 2000 m
    assert kpi["total_saving_km"] == pytest.approx(0.7)


def test_platform_profit(kpi):
    p = Params()
    assert (p.fare_solo_cny_per_km, p.fare_pooled_cny_per_km, p.driver_pay_cny_per_km) == (5.0, 3.5, 2.0)
    # fares on solo distance: order 0 5 · 1.5 = 7.5; pooled 3.5 · (1.2 + 1.5) = 9.45  -> 16.95
    # driver pay: 2 · 3.5 km occupied = 7.0                                          -> profit 9.95
    assert kpi["platform_profit_cny"] == pytest.approx(9.95)
    # alternative: 5 CNY/km of un-shared ride + 3.5 CNY/km of shared ride:
    #   order 0: 5 · 1.5 = 7.5;  A: 5 · (1.5 - 1.0) + 3.5 · 1.0 = 6.0;  B: same 6.0   -> 19.5 - 7.0 = 12.5
    assert kpi["platform_profit_alt_cny"] == pytest.approx(12.5)


def test_platform_profit_other_fares(tab):
    # Solo 6, pooled 4, pay 1 CNY/km: 6 · 1.5 + 4 · 2.7 - 1 · 3.5 = 9 + 10.8 - 3.5 = 16.3
    # alt: 6 · 1.5 + 2 · (6 · 0.5 + 4 · 1.0) - 3.5 = 9 + 14 - 3.5 = 19.5
    params = Params().replace(fare_solo_cny_per_km=6.0, fare_pooled_cny_per_km=4.0, driver_pay_cny_per_km=1.0)
    out = kpis(tab, occupied_distance_m(EVENTS, TRAJ), params)
    assert out["platform_profit_cny"] == pytest.approx(16.3)
    assert out["platform_profit_alt_cny"] == pytest.approx(19.5)


def test_no_pooling_gives_nan_pool_averages():
    # Only order 0 of the log (a solo ride): pooled averages are undefined, saving = 1.5 - 1.5 = 0.
    events = EVENTS[EVENTS["order"].isin([0])]
    t = passenger_table(events, SOLO_M[:1], REQUEST_S[:1], TRAJ)
    out = kpis(t, occupied_distance_m(events, TRAJ), Params())
    assert out["response_rate"] == 1.0 and out["pairing_ratio"] == 0.0
    assert np.isnan(out["avg_detour_m"]) and np.isnan(out["avg_shared_m"])
    assert out["total_saving_km"] == 0.0
    assert out["platform_profit_cny"] == pytest.approx(7.5 - 2 * 1.5)  # fare 5 · 1.5, pay 2 · 1.5


def test_no_pair_saves_exactly_nothing():
    """Solo rides whose solo distances and odometer legs sum to the same length in different float roundings:
    the saving is Σ over pairs, none here, so exactly 0 (not the 1e-13 of the two sums' difference)."""
    events = event_log(
        [
            (0.0, "request", 0, -1, 10, "", -1, False),
            (0.0, "request", 1, -1, 20, "", -1, False),
            (10.0, "assign", 0, 0, -1, "vacant", -1, False),
            (10.0, "assign", 1, 1, -1, "vacant", -1, False),
            (20.0, "pickup", 0, 0, 10, "", -1, False),
            (20.0, "pickup", 1, 1, 20, "", -1, False),
            (40.0, "dropoff", 0, 0, 11, "", -1, False),
            (40.0, "dropoff", 1, 1, 21, "", -1, False),
        ]
    )
    traj = trajectories(
        [
            [(1, 0.0, 0.0), (10, 20.0, 0.1), (11, 40.0, 1000.2)],
            [(2, 0.0, 0.0), (20, 20.0, 0.2), (21, 40.0, 3333.3)],
        ]
    )
    solo = np.array([1000.1, 3333.1])
    occupied = occupied_distance_m(events, traj)
    assert float(solo.sum()) / 1000 - float(occupied.sum()) / 1000 != 0.0  # the float noise the rule removes
    out = kpis(passenger_table(events, solo, np.zeros(2), traj), occupied, Params())
    assert out["pairs"] == 0 and out["total_saving_km"] == 0.0
    assert out["total_occupied_km"] == pytest.approx(out["total_solo_served_km"])


def test_hourly(tab):
    h = hourly(tab, start_hour=8)
    assert h["hour"].tolist() == [8, 9]  # orders 0-2 requested in 8:00-9:00, order 3 at 9:01:40
    assert h["orders"].tolist() == [3, 1]
    assert h["response_rate"].tolist() == pytest.approx([1.0, 0.0])
    first, second = h.iloc[0], h.iloc[1]
    assert first["pairing_ratio"] == pytest.approx(2 / 3)  # 2 pooled of 3 served
    assert first["avg_detour_m"] == pytest.approx(150.0)
    assert first["avg_shared_m"] == pytest.approx(1000.0)
    # the pair's saving, counted once (on A, the earlier order): 1200 + 1500 - 2000 = 700 m
    assert first["total_saving_km"] == pytest.approx(0.7)
    assert first["avg_pickup_m"] == pytest.approx(1100.0 / 3)
    assert first["avg_pickup_time_s"] == pytest.approx(40.0)
    # the cancelled hour: nobody served, so the ratios and means are undefined and nothing was saved
    assert np.isnan(second["pairing_ratio"]) and np.isnan(second["avg_detour_m"])
    assert np.isnan(second["avg_pickup_m"]) and np.isnan(second["avg_pickup_time_s"])
    assert second["total_saving_km"] == 0.0


def test_hourly_default_start_hour(tab):
    assert hourly(tab)["hour"].tolist() == [0, 1]


def direct_count(events: pd.DataFrame, state: str, t: float) -> int:
    """How many passengers are in ``state`` at ``t``, counted order by order from the log (the definitions of
    :func:`state_spells`, written out; an event at t has happened at t)."""
    at: dict[int, dict[str, float]] = {}
    partner: dict[int, int] = {}
    for row in events.itertuples():
        if row.order >= 0:
            at.setdefault(row.order, {})[row.event] = row.t_s
        if row.event == "assign" and row.partner >= 0:
            partner[row.order], partner[row.partner] = row.partner, row.order

    def by(o: int, name: str) -> bool:
        return name in at[o] and at[o][name] <= t

    def aboard(o: int) -> bool:
        return by(o, "pickup") and not by(o, "dropoff")

    if state == "waiting":
        return sum(by(o, "request") and not by(o, "assign") and not by(o, "cancel") for o in at)
    if state == "serving":
        return sum(by(o, "assign") and not by(o, "dropoff") for o in at)
    if state == "pooled":
        return sum(o in partner and aboard(o) and aboard(partner[o]) for o in at)
    return sum(by(o, "cancel") for o in at)


def test_timeline_spells_count_the_states():
    spells = state_spells(EVENTS)
    assert set(spells) == set(TIMELINE_STATES)
    t = np.array([0.0, 25.0, 50.0, 120.0, 210.0, 3750.0, 3790.0])
    assert count_at(spells["waiting"], t).tolist() == [1, 2, 0, 0, 0, 1, 0]
    assert count_at(spells["serving"], t).tolist() == [0, 1, 3, 3, 1, 0, 0]
    # orders 1 and 2 both aboard from 110 s (2's pick-up) to 210 s (1's drop-off); the join names 1 only
    assert count_at(spells["pooled"], t).tolist() == [0, 0, 0, 2, 0, 0, 0]
    assert count_at(spells["cancelled"], t).tolist() == [0, 0, 0, 0, 0, 0, 1]
    for state in TIMELINE_STATES:
        assert count_at(spells[state], t).tolist() == [direct_count(EVENTS, state, x) for x in t]


def test_timeline_means_are_exact_time_averages():
    spells = state_spells(EVENTS)
    # pooled: 0 over [100, 110), 2 over [110, 120); serving over [0, 60): 1 from 10 s, 2 from 30 s, 3 from 50 s
    assert mean_count(spells["pooled"], np.array([100.0, 120.0])).tolist() == pytest.approx([1.0])
    assert mean_count(spells["serving"], np.array([0.0, 60.0])).tolist() == pytest.approx([(20 + 40 + 30) / 60])
    # every event time is a whole second: the mean over a bin is the mean of the counts at its seconds
    edges = np.array([0.0, 60.0, 120.0, 300.0, 3600.0, 3800.0])
    for state in TIMELINE_STATES:
        seconds = [count_at(spells[state], np.arange(a, b)).mean() for a, b in itertools.pairwise(edges)]
        assert mean_count(spells[state], edges) == pytest.approx(seconds)


def test_timeline_of_an_empty_log():
    spells = state_spells(EVENTS.iloc[:0])
    assert all(count_at(spells[s], np.array([5.0])).tolist() == [0] for s in TIMELINE_STATES)
    assert mean_count(spells["waiting"], np.array([0.0, 60.0])).tolist() == [0.0]


# ------------------------------------------------------------------ decision budget
def hand_made_rounds(parts: list[tuple[float, float, float, float]]) -> pd.DataFrame:
    """Rounds with the given (strategy build, solver build, solve, extract) seconds."""
    return pd.DataFrame(parts, columns=["strategy_build_s", "solver_build_s", "solve_s", "extract_s"])


def test_rounds_over_the_decision_budget_are_the_strictly_slower_ones():
    """A round's decision is its four parts summed; one taking exactly the budget is within it."""
    rounds = hand_made_rounds([(0.1, 0.0, 0.2, 0.0), (0.25, 0.05, 0.5, 0.2), (0.5, 0.0, 0.0, 0.0), (0.0,) * 4])
    assert decision_times(rounds) == pytest.approx([0.3, 1.0, 0.5, 0.0])
    assert over_budget(rounds, 0.5).tolist() == [False, True, False, False]
    assert over_budget(rounds, 1e-9).tolist() == [True, True, True, False]
    assert not over_budget(rounds, 1e9).any()
    assert over_budget(rounds.iloc[:0], 0.5).tolist() == []
    # the budget counts like rounds_over_dt against Δt: the same rounds for the same threshold
    assert decision_kpis(rounds, 0.5)["rounds_over_dt"] == float(over_budget(rounds, 0.5).sum())


def test_the_budget_kpi_is_labelled_and_a_timing_kpi():
    """It depends on the clock, so tests comparing runs leave it out with the other timings."""
    assert BUDGET_KPI == "rounds_over_budget" and BUDGET_KPI in TIMING_KPIS
    assert KPI_LABELS[BUDGET_KPI] == "Rounds slower than the decision budget"
