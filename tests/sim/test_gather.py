"""The round state's compiled gathers (rpbench.sim.gather) equal the numpy expressions they replace."""

from __future__ import annotations

import numpy as np

from rpbench.sim import gather


def test_the_gathers_equal_numpy_on_random_fleets_and_orders():
    rng = np.random.default_rng(0)
    for _ in range(100):
        n_o, n_v = int(rng.integers(1, 40)), int(rng.integers(0, 30))
        origin, destination = rng.integers(0, 100, n_o), rng.integers(0, 100, n_o)
        solo, request = rng.random(n_o) * 5000, np.sort(rng.random(n_o) * 3600)
        pickup_odo = np.where(rng.random(n_o) < 0.5, rng.random(n_o) * 1e5, np.nan)
        state = rng.integers(0, 6, n_o).astype(np.int8)
        load, paired, on_duty = rng.integers(0, 3, n_v), rng.random(n_v) < 0.3, rng.random(n_v) < 0.8
        v0, v1 = gather.fleet_split(load, paired, on_duty)
        assert v0.tolist() == np.flatnonzero((load == 0) & on_duty).tolist()
        assert v1.tolist() == np.flatnonzero((load == 1) & ~paired & on_duty).tolist()
        p = rng.permutation(n_o)[: int(rng.integers(0, n_o + 1))]
        t, dt = float(rng.integers(0, 400) * 10), 10.0
        got = gather.passengers(p, origin, destination, solo, request, t, dt)
        waited = np.maximum(1, np.ceil((t - request[p]) / dt - 1e-9)).astype(np.int64)
        for g, w in zip(got, (origin[p], destination[p], solo[p], request[p], waited), strict=True):
            assert g.dtype == w.dtype and g.tolist() == w.tolist()
        order = rng.integers(0, n_o, len(v1))
        node_next, pre_next, odo_next = rng.integers(0, 100, len(v1)), rng.random(len(v1)), rng.random(len(v1)) * 1e5
        got = gather.riders(order, state, 3, origin, destination, solo, pickup_odo, node_next, pre_next, odo_next)
        onboard = state[order] == 3
        want = (
            np.where(onboard, node_next, origin[order]),
            np.where(onboard, odo_next - pickup_odo[order], 0.0),
            np.where(onboard, pre_next, 0.0),
            onboard,
            origin[order],
            destination[order],
            solo[order],
        )
        for g, w in zip(got, want, strict=True):
            assert g.dtype == w.dtype and np.array_equal(g, w, equal_nan=g.dtype.kind == "f")
