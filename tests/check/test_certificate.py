"""The bound certificate: every pair a strategy formed is an edge of the upper bound's graph (docs/bound.md) whose
weight covers its realised saving, and the strategy's saving is at most the bound — with the checker's own pair
geometry, which these tests also hold to the bound's stored pairs."""

from __future__ import annotations

import numpy as np
import pandas as pd

from check.tamper import assert_fails, events, joined_pair, set_kpi
from rpbench import results
from rpbench.check import bound_weights
from rpbench.check.folder import read_folder


def test_a_shortened_shared_ride_fails_the_bound_certificate(folder):
    """5 km less occupied driving after a pair's last drop-off: its saving exceeds the bound's edge weight."""
    ev = events(folder, "mb")
    joining, first, _ = joined_pair(folder)
    drops = ev[(ev["event"] == "dropoff") & ev["order"].isin([joining, first])]
    last = drops.sort_values("t_s").iloc[-1]
    traj = results.load_trajectories(folder / "runs" / "mb" / "trajectories.npz")
    lo, hi = traj["vehicle_offsets"][int(last["vehicle"])], traj["vehicle_offsets"][int(last["vehicle"]) + 1]
    k = (
        lo
        + np.flatnonzero((np.abs(traj["t_s"][lo:hi] - last["t_s"]) < 1e-6) & (traj["node"][lo:hi] == last["node"]))[0]
    )
    traj["odo_m"][k:hi] -= 5000.0
    results.save_trajectories(folder / "runs" / "mb" / "trajectories.npz", traj)
    found = assert_fails(folder, "bound-certificate", "exceeds the bound's edge weight", run="mb")
    assert "movement" in found and "kpi" in found


def test_a_lowered_upper_bound_fails_its_own_kpi_and_every_certificate(folder):
    """A bound edited below a strategy's saving fails the bound's ``kpi`` and the strategies' certificates."""
    set_kpi(folder, "bound", "total_saving_km", lambda v: 0.001)
    found = assert_fails(folder, "kpi", "KPI total_saving_km: reported 0.001", run="bound")
    assert any(m.startswith("mb: saving") and "exceeds the upper bound" in m for m in found["bound-certificate"])


def test_an_edge_weighs_its_better_orientation_and_the_bounds_pairs_are_edges(base):
    """An edge's weight is the larger saving of its two orientations; the bound's pairs are edges of that weight."""
    f = read_folder(base)
    a, b = np.triu_indices(min(f.n, 40), 1)
    inputs = (f.distances, f.orders, f.solo, f.params)
    weight, edge = bound_weights(*inputs, a, b)
    a_first, _ = bound_weights(*inputs, a, b, a_first_only=True)
    b_first, _ = bound_weights(*inputs, b, a, a_first_only=True)
    assert np.array_equal(weight, np.fmax(a_first, b_first)) and np.array_equal(edge, np.isfinite(weight))
    assert np.array_equal(bound_weights(*inputs, b, a)[0], weight) and edge.any() and not edge.all()
    pairs = pd.read_csv(base / "runs" / "bound" / "pairs.csv.gz")
    row = pd.Series(np.arange(f.n), index=f.orders["order_id"])
    weight, edge = bound_weights(*inputs, row[pairs["first_id"]].to_numpy(), row[pairs["second_id"]].to_numpy())
    assert len(pairs) and edge.all() and np.allclose(weight, pairs["saving_m"], rtol=0, atol=1e-6)
