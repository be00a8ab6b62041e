"""The replication audit: what it recomputes from a run's passenger records, and what it catches."""

import pandas as pd

from rpbench.results.replication_audit import audit_run


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
    bad, checked = audit_run(records(), row())
    assert bad == {} and checked["assignment"] > 0 and checked["accounting"] > 0


def test_a_wrong_reported_saving_is_named():
    bad, _ = audit_run(records(), row(total_saving_km=4.0))
    assert "accounting" in bad and "total_saving_km" in bad["accounting"][0]


def test_a_passenger_served_twice_and_a_one_sided_partner_are_named():
    rec = records()
    rec.loc[2, "order_id"] = 1
    bad, _ = audit_run(rec, row())
    assert any("served twice" in m for m in bad["assignment"])
    rec = records()
    rec.loc[1, "partner"] = 3
    bad, _ = audit_run(rec, row())
    assert any("not mutual" in m for m in bad["assignment"])


def test_a_two_request_trip_is_one_assignment_but_two_strangers_are_not():
    rec = records()
    rec.loc[1, ["assign_s", "request_s"]] = [10.0, 5.0]  # RTV: both partners taken by vehicle 0 in one round
    assert audit_run(rec, row())[0] == {}
    rec.loc[2, ["vehicle", "assign_s"]] = [0, 10.0]
    bad, _ = audit_run(rec, row())
    assert any("not one trip" in m for m in bad["assignment"])
