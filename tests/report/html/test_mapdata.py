"""The map's layers are the event log's pairs, solo trips and cancellations, counted independently here."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.report.html.mapdata import MAX_DRAWN, layers, map_payload


def direct_layers(events: pd.DataFrame) -> tuple[set, set, set]:
    """Pairs (frozensets of orders), solo orders and cancelled orders, from a per-order pivot of the log."""
    by = events.pivot_table(index="order", columns="event", values="t_s", aggfunc="first")
    delivered = set(by.index[by["dropoff"].notna()])
    links = events[(events["event"] == "assign") & (events["partner"] >= 0)]
    pairs = {frozenset((int(a), int(b))) for a, b in zip(links["order"], links["partner"], strict=True)}
    pairs = {p for p in pairs if p <= delivered}
    mates = set(links["order"]) | set(links["partner"])
    solo = {int(o) for o in delivered if o not in mates}
    cancelled = {int(o) for o in by.index[by["cancel"].notna()]} if "cancel" in by else set()
    return pairs, solo, cancelled


def test_layers_are_the_event_logs(toy_run):
    orders = results.read_csv(toy_run / "orders.csv.gz")
    for run in ("mb", "fl", "np"):
        events = results.read_csv(toy_run / "runs" / run / "events.csv.gz")
        got = layers(events, orders["origin"].to_numpy())
        pairs, solo, cancelled = direct_layers(events)
        pooled = got["pooled"]
        assert {frozenset(pooled["orders"][2 * i : 2 * i + 2]) for i in range(len(pooled["t"]))} == pairs
        assert set(got["solo"]["orders"]) == solo and set(got["cancelled"]["orders"]) == cancelled
        kpis = results.read_csv(toy_run / "kpis.csv").set_index(["run", "kpi"])["value"]
        assert len(pooled["t"]) == kpis[(run, "pairs")]  # the KPI table's count of pairs too
        # the four stops are the pick-ups, then the drop-offs, each in time order; t is the first pick-up
        ev = events.set_index(["order", "event"])
        for i in range(len(pooled["t"])):
            a, b = pooled["orders"][2 * i : 2 * i + 2]
            picks = sorted(
                [
                    (ev.loc[(a, "pickup"), "t_s"], ev.loc[(a, "pickup"), "node"]),
                    (ev.loc[(b, "pickup"), "t_s"], ev.loc[(b, "pickup"), "node"]),
                ]
            )
            drops = sorted(
                [
                    (ev.loc[(a, "dropoff"), "t_s"], ev.loc[(a, "dropoff"), "node"]),
                    (ev.loc[(b, "dropoff"), "t_s"], ev.loc[(b, "dropoff"), "node"]),
                ]
            )
            assert pooled["nodes"][4 * i : 4 * i + 4] == [int(n) for _, n in picks + drops]
            assert pooled["t"][i] == int(picks[0][0])  # whole seconds, floored
        assert np.all(np.diff(pooled["t"]) >= 0)  # sorted by time, for the page's window filter
        cancel_nodes = orders["origin"].to_numpy()[got["cancelled"]["orders"]]
        assert got["cancelled"]["nodes"] == cancel_nodes.tolist()


def test_the_payload_covers_the_simulated_runs(toy_run):
    payload = map_payload(toy_run)
    assert not isinstance(payload, str)
    assert [r["name"] for r in payload["runs"]] == ["np", "mb", "fl"]
    assert payload["offline"] == ["Upper bound"]
    n = len(payload["nodes"]["lon"])
    every = [v for r in payload["runs"] for layer in ("pooled", "solo", "cancelled") for v in r[layer]["nodes"]]
    assert every and min(every) >= 0 and max(every) < n and max(payload["edges"]) < n
    assert payload["runs"][payload["first_run"]]["name"] != "np"  # the map opens on a run that pooled
    assert payload["max_drawn"] == MAX_DRAWN
    assert payload["period"]["window_s"] == 600.0


def test_no_map_without_the_inputs(toy_run, tmp_path):
    import shutil

    copy = tmp_path / "light"
    shutil.copytree(toy_run, copy, ignore=shutil.ignore_patterns(*results.layout.HEAVY))
    assert "light copy leaves out" in map_payload(copy)
