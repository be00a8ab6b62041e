"""The shared pair forecast of the clairvoyant strategies: its vectorised walk against a per-node walk on the
toy city, its round windows, and the V1 pick-up times it is given."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import line_network, round_state, scenario_of

from rpbench.geometry import pool
from rpbench.scenarios import build_scenario
from rpbench.strategies.foresight import Foresight, PickupTimes


def walked(scenario, sight: Foresight, a: int, b: int, t_lo, t_hi, t_pick, t_early) -> float:
    """The forecast, one node at a time: the first node of P_A that the vehicle has next at some position
    ``x`` of the window (``(c_prev, c_h]``; ``x = 0`` before the pick-up, A14) with ``c_h - x + l(h, o_B) <= R̄``,
    valued by POOL there (NaN: none, or POOL infeasible)."""
    p, dist = scenario.params, sight.dist
    o_a, d_a, o_b, d_b = (
        int(x) for x in (sight.origin[a], sight.destination[a], sight.origin[b], sight.destination[b])
    )
    if t_lo > t_hi or dist[o_a, d_a] == 0 or dist[o_b, d_b] == 0:
        return math.nan
    v = p.speed_mps
    s_lo, s_hi = v * max(0.0, t_lo - t_pick), v * max(0.0, t_hi - t_early)
    previous = -math.inf
    for h in scenario.network.distances().path_nodes(o_a, d_a):
        c = float(dist[o_a, h])
        x_hi = min(s_hi, c)  # the latest position with h next: the shortest way left to h
        x_lo = max(s_lo, previous, c - (p.max_pickup_m - dist[h, o_b]))
        if x_hi >= x_lo and x_hi > previous:
            r = pool(
                dist,
                o_a,
                d_a,
                o_b,
                d_b,
                h=h,
                delta=c,
                pre=c - x_hi,
                max_pickup_m=p.max_pickup_m,
                max_detour_m=p.max_detour_m,
            )
            return float(r.saving) if bool(r.feasible) else math.nan
        previous = c
    return math.nan


@pytest.mark.parametrize("seed", [0, 1])
def test_the_vectorised_forecast_is_the_per_node_walk_on_the_toy_city(seed):
    scenario = build_scenario("toy", sample=0.3, seed=seed)
    sight = Foresight(scenario)
    rng = np.random.default_rng(seed)
    d = sight.dist
    o, dd, solo = sight.origin, sight.destination, sight.solo
    # pairs whose first passenger's detour can be met at all: the others are NaN before any walk
    a, b = rng.integers(0, sight.n, 20_000), rng.integers(0, sight.n, 20_000)
    near = (a != b) & (d[o[a], o[b]] + d[o[b], dd[a]] - solo[a] <= scenario.params.max_detour_m)
    a, b = a[near][:600], b[near][:600]
    m = len(a)
    t_pick = rng.uniform(0.0, 300.0, m)
    t_lo = t_pick + rng.uniform(-120.0, 400.0, m)  # B may be revealed before A is on board
    t_hi = t_lo + rng.uniform(-30.0, 200.0, m)  # an empty window now and then
    t_early = t_pick - np.where(rng.random(m) < 0.5, rng.uniform(0.0, 200.0, m), 0.0)  # a range of pick-up times
    got = sight.forecast(a, b, t_lo, t_hi, t_pick, t_early)
    want = np.array([walked(scenario, sight, *args) for args in zip(a, b, t_lo, t_hi, t_pick, t_early, strict=True)])
    assert np.isfinite(want).sum() > 100 and np.isnan(want).sum() > 20  # both outcomes are exercised
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got[np.isfinite(got)], want[np.isfinite(want)], atol=1e-6)
    # without t_pick_early the pick-up time is t_pick
    np.testing.assert_array_equal(
        sight.forecast(a, b, t_lo, t_hi, t_pick), sight.forecast(a, b, t_lo, t_hi, t_pick, t_pick)
    )


def test_a_pair_joined_at_the_origin_saves_what_pool_says():
    """B revealed before A is picked up: the vehicle turns at o_A (A14), the saving is POOL's with δ = 0."""
    net = line_network(7)
    scenario = scenario_of(net, [(0.0, 0, 6), (15.0, 1, 5)], [0])
    sight = Foresight(scenario)
    p = scenario.params
    e = sight.forecast(np.array([0]), np.array([1]), np.array([20.0]), np.array([100.0]), np.array([60.0]))
    r = pool(sight.dist, sight.origin[0], sight.destination[0], sight.origin[1], sight.destination[1],
             max_pickup_m=p.max_pickup_m, max_detour_m=p.max_detour_m)  # fmt: skip
    assert e[0] == pytest.approx(float(r.saving)) == pytest.approx(4000.0)  # FOLO: L = 1000 + 4000 + 1000
    # once the vehicle has passed o_B the pick-up only grows: a partner revealed too late cannot join
    late = sight.forecast(np.array([0]), np.array([1]), np.array([1000.0]), np.array([1080.0]), np.array([60.0]))
    assert np.isnan(late[0])


def test_round_windows_follow_the_simulators_reveal_and_cancel_rules():
    net = line_network(4)
    scenario = scenario_of(net, [(0.0, 0, 3), (15.0, 1, 3), (20.0, 2, 3)], [0], patience_s=90.0)
    sight = Foresight(scenario)
    np.testing.assert_array_equal(sight.first_round, [0.0, 20.0, 20.0])
    np.testing.assert_array_equal(sight.last_round, [90.0, 100.0, 110.0])  # cancelled once t - t_req > K
    np.testing.assert_array_equal(sight.join_from(np.array([1, 2]), np.array([30.0, 0.0]), 10.0), [30.0, 20.0])


def test_v1_pick_up_times_come_from_the_round_that_assigned_them():
    net = line_network(6)
    v = 30.0 / 3.6
    state = round_state(
        net,
        [(4, 5)],
        [],
        t=50.0,
        occupied=[
            {"node": 1, "origin": 1, "destination": 5, "onboard": False},  # order 1: assigned at t = 40, 500 m away
            {"node": 3, "origin": 1, "destination": 5, "delta": 2000.0, "pre": 400.0, "onboard": True},  # order 2
        ],
    )
    times = PickupTimes(3, v, default_s=120.0)
    assert times.mean_s() == 120.0
    times.offered(40.0, np.array([1, 0]), np.array([state.v1_vehicle[0], 7]), np.array([500.0, 900.0]))
    times.observe(state)
    assert times.pick_s[1] == pytest.approx(40.0 + 500.0 / v) and times.mean_s() == pytest.approx(500.0 / v)
    # on board: driven δ - pre = 1600 m since the pick-up
    np.testing.assert_allclose(times.of_v1(state, np.array([1, 2])), [40.0 + 500.0 / v, 50.0 - 1600.0 / v])
