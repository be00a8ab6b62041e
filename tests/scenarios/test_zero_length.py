"""Zero-length orders (origin = destination node, as snapping makes a few real ones): counted in the scenario
summary, served solo and never pooled by any strategy or oracle, and a run that pools one fails ``rpbench
check`` (docs/simulator.md)."""

from __future__ import annotations

import csv
import dataclasses
import gzip
import io
import json

import numpy as np
import pytest
from helpers import network_from_edges, scenario_of, write_gz

from rpbench import geometry
from rpbench.backends.presets import load_preset
from rpbench.cli import main
from rpbench.harness.comparison import simulate_strategy
from rpbench.strategies import candidates

# A rides 0 -> 3; the zero-length order B waits at node 1 (on A's path) or 9 (a spur off it).
NETWORK = [(0, 1, 1000.0), (1, 2, 1000.0), (2, 3, 1000.0), (1, 9, 500.0)]
CASES = {
    "B on A's path": [(0.0, 0, 3), (10.0, 1, 1)],
    "B off A's path": [(0.0, 0, 3), (10.0, 9, 9)],
    "B first": [(0.0, 1, 1), (10.0, 0, 3)],
}


def without_the_rule(g, max_pickup_m, order_rule="min_feasible"):
    """choose_order as before the rule: zero-length orders could pool."""
    r = ORIGINAL(g, max_pickup_m, order_rule)
    ok = g.fofo_ok | g.folo_ok if order_rule == "min_feasible" else np.where(r.fofo, g.fofo_ok, g.folo_ok)
    return dataclasses.replace(r, feasible=ok & (g.pk <= max_pickup_m + geometry.TOLERANCE_M))


ORIGINAL = geometry.choose_order


@pytest.fixture(scope="module")
def preset():
    return load_preset("highs")


def test_the_summary_counts_zero_length_orders():
    sc = scenario_of(network_from_edges(NETWORK), CASES["B off A's path"], vehicles=[0])
    assert sc.summary()["zero_length_orders"] == 1


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("strategy", ["mb", "rtv", "fl-nd", "fl"])
def test_no_strategy_pools_a_zero_length_order(preset, case, strategy):
    sc = scenario_of(network_from_edges(NETWORK), CASES[case], vehicles=[0])
    run = simulate_strategy(sc, strategy, preset, progress=False)
    assert not run.passengers["pooled"].any()
    assert run.kpis["total_saving_km"] >= 0


def test_mb_pooled_one_at_a_loss_before_the_rule(preset, monkeypatch):
    monkeypatch.setattr(candidates, "choose_order", without_the_rule)
    # the join options' numpy passes (the compiled pass's reference) are the ones that call choose_order
    monkeypatch.setattr(candidates, "ORDER_RULES", ())
    sc = scenario_of(network_from_edges(NETWORK), CASES["B off A's path"], vehicles=[0])
    run = simulate_strategy(sc, "mb", preset, progress=False)
    assert run.passengers["pooled"].all() and run.kpis["total_saving_km"] < 0


def test_no_pair_of_pool_holds_a_zero_length_order():
    dist = network_from_edges(NETWORK).distances().dist
    r = geometry.pool(dist, [0, 0, 0], [3, 3, 3], [1, 4, 2], [1, 4, 3], max_pickup_m=1e9, max_detour_m=1e9)
    assert r.feasible.tolist() == [False, False, True]


def run_with_same_node_orders(tmp_path, data, out) -> dict:
    """A run of the fake data folder whose every third order has its destination set to its origin."""
    path = data / "demand_0800_0900" / "orders" / "2017-05-01.csv.gz"
    with gzip.open(path, "rt") as fh:
        rows = list(csv.reader(fh))
    o, d = rows[0].index("origin_id"), rows[0].index("destination_id")
    for row in rows[1::3]:
        row[d] = row[o]
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    write_gz(path, buffer.getvalue())
    argv = ["run", "--scenario", "haikou-peak", "--data", str(data), "--sample", "1.0", "--strategies", "mb,rtv"]
    assert main([*argv, "--no-progress", "--out", str(out)]) == 0
    return json.loads((out / "meta.json").read_text())


def test_the_checker_fails_a_run_that_pools_a_zero_length_order(capsys, tmp_path, fake_data, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(candidates, "choose_order", without_the_rule)
    monkeypatch.setattr(geometry, "choose_order", without_the_rule)
    monkeypatch.setattr(candidates, "ORDER_RULES", ())  # the numpy passes, which call choose_order
    out = tmp_path / "old"
    meta = run_with_same_node_orders(tmp_path, fake_data, out)
    assert meta["scenario"]["summary"]["zero_length_orders"] > 0
    capsys.readouterr()
    assert main(["check", str(out)]) != 0
    text, _ = capsys.readouterr()
    assert "[service]" in text and "zero-length trip" in text


def test_the_checker_passes_runs_under_the_rule(capsys, tmp_path, fake_data, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "new"
    meta = run_with_same_node_orders(tmp_path, fake_data, out)
    assert meta["scenario"]["summary"]["zero_length_orders"] > 0
    capsys.readouterr()
    assert main(["check", str(out)]) == 0
