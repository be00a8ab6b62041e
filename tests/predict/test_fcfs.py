"""The FCFS validation simulator on a toy grid (TR-B-style accuracy check)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.predict import solve_prediction_model
from rpbench.predict.fcfs import simulate, validate

from .conftest import make_instance


def test_fcfs_agrees_with_the_prediction_on_a_toy_grid():
    inst = make_instance(seed=3, size=6, n_od=20, rate_per_h=3, max_pickup_m=1500, max_detour_m=1500, grid_seed=3)
    model = inst.model()
    pred = solve_prediction_model(model)
    res = simulate(model, hours=150, seed=1)
    metrics, table = validate(pred, res, min_samples=100)
    assert metrics["ods_compared"] >= 10
    assert res.orders.sum() == pytest.approx(inst.rates.total_per_s * 150 * 3600, rel=0.05)
    # The model is an approximation, but a good one at this scale (TR-B grid: MAPE of P_w ~2-9 %).
    assert metrics["pairing_prob"]["mape_pct"] < 12
    assert metrics["ride_m"]["mape_pct"] < 3
    assert abs(metrics["overall"]["pred_pairing_rate"] - metrics["overall"]["sim_pairing_rate"]) < 0.05
    # Paired orders pair in twos: as many seeker pairings as taker pairings.
    assert res.paired.sum() == pytest.approx(2 * res.as_seeker.sum(), abs=0.02 * res.paired.sum() + 5)


def test_fcfs_without_pairs_never_pairs():
    inst = make_instance(seed=4, size=5, n_od=8, max_pickup_m=1e-6, include_origin_state=False)
    model = inst.model()
    res = simulate(model, hours=5, seed=0)
    assert res.paired.sum() == 0
    np.testing.assert_allclose(res.ride_m, res.orders * model.space.solo_m)
