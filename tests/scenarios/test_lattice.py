"""The lattice city: every block one batch interval long, deterministic per seed, its history at the day's rate."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.exceptions import ParameterError
from rpbench.scenarios import build_scenario
from rpbench.scenarios.lattice import HORIZON_S, LATTICE_BASE_ORDERS, lattice_network


@pytest.mark.parametrize("dt_s", [10.0, 30.0])
def test_every_block_takes_one_batch_interval(dt_s):
    sc = build_scenario("lattice", sample=0.3, seed=1, param_overrides={"dt_s": dt_s})
    net = sc.network
    assert np.allclose(net.arc_length_m / sc.params.speed_mps, dt_s)
    assert net.n_nodes == 100 and sc.provenance["block_m"] == pytest.approx(sc.params.speed_mps * dt_s)
    steps = net.distances().dist / (sc.params.speed_mps * dt_s)
    assert np.allclose(steps, np.rint(steps))  # every distance whole blocks


def test_orders_and_fleet_follow_the_sample_and_the_seed():
    a = build_scenario("lattice", sample=0.8, seed=3)
    b = build_scenario("lattice", sample=0.8, seed=3)
    c = build_scenario("lattice", sample=0.8, seed=4)
    assert len(a.orders) == round(0.8 * LATTICE_BASE_ORDERS) and len(a.fleet) == 20
    assert (a.orders.request_s < HORIZON_S).all() and a.horizon_s == HORIZON_S
    assert np.array_equal(a.orders.origin, b.orders.origin) and not np.array_equal(a.orders.origin, c.orders.origin)
    assert (a.orders.origin != a.orders.destination).all()


def test_its_history_is_past_hours_at_the_days_rate():
    """Past hours of other seeds (never the day's own draws), each with the day's orders per hour."""
    sc = build_scenario("lattice", sample=0.3, seed=0)
    history = sc.demand.history
    assert history is not None and history.days == 10
    assert len(history.request_s) == 10 * round(30 * 3600.0 / HORIZON_S)
    assert history.request_s.max() < 3600.0


def test_bad_lattices_are_one_line_errors():
    with pytest.raises(ParameterError, match="size"):
        lattice_network(1, 100.0)
    with pytest.raises(ParameterError, match="block length"):
        lattice_network(4, 0.0)
