"""RTV-2 properties R1-R9 of docs/algorithms.md §3.4 on hand-made round states."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers import network_from_edges, round_state
from scipy.optimize import linear_sum_assignment

from rpbench.backends.presets import load_preset
from rpbench.model import TripPackingModel
from rpbench.scenarios.base import Params
from rpbench.strategies import Kind, make_strategy


@pytest.fixture(scope="module")
def solve():
    preset = load_preset("highs")
    backend = preset.adapter()
    return lambda model: backend.solve(model, preset.options)


def star(leaves: int = 6, arm: float = 500.0):
    return network_from_edges([(0, i, arm) for i in range(1, leaves + 1)], name="star")


def grid(size: int = 4, block: float = 400.0):
    edges = []
    for i in range(size * size):
        r, c = divmod(i, size)
        if c < size - 1:
            edges.append((i, i + 1, block + 7.0 * i))
        if r < size - 1:
            edges.append((i, i + size, block + 5.0 * i))
    return network_from_edges(edges, name="grid")


def random_state(rng, net, n_pass, n_vac, n_occ=0, params=None):
    nodes = net.node_id
    pas = []
    for _ in range(n_pass):
        o, d = rng.choice(nodes, size=2, replace=False)
        pas.append((int(o), int(d)))
    vac = [(int(rng.choice(nodes)), float(rng.uniform(0, 100))) for _ in range(n_vac)]
    occ = []
    for _ in range(n_occ):
        o, d = rng.choice(nodes, size=2, replace=False)
        occ.append({"node": int(o), "origin": int(o), "destination": int(d), "delta": 0.0, "pre": 0.0, "onboard": True})
    return round_state(net, pas, vac, occupied=occ, params=params)


def brute_force(model: TripPackingModel, max_served: bool = False) -> float:
    """Best packing by enumeration over one column (or none) per vehicle."""
    per_vehicle = [np.flatnonzero(model.col_vehicle == v) for v in range(model.n_vehicles)]
    best = 0.0
    for combo in itertools.product(*[[-1, *cols] for cols in per_vehicle]):
        chosen = [c for c in combo if c >= 0]
        reqs = [r for c in chosen for r in (model.col_request1[c], model.col_request2[c]) if r >= 0]
        if len(reqs) != len(set(reqs)):
            continue
        best = max(best, len(reqs) if max_served else float(model.values[chosen].sum()))
    return best


def greedy(model: TripPackingModel) -> float:
    size = 1 + (model.col_request2 >= 0)
    order = np.lexsort((-model.values, -size))
    used_v, used_r, total = set(), set(), 0.0
    for c in order:
        reqs = {int(r) for r in (model.col_request1[c], model.col_request2[c]) if r >= 0}
        if model.col_vehicle[c] in used_v or reqs & used_r:
            continue
        used_v.add(int(model.col_vehicle[c]))
        used_r |= reqs
        total += model.values[c]
    return total


def test_r3_ilp_beats_greedy_and_equals_brute_force(solve):
    rng = np.random.default_rng(0)
    net = grid()
    for _ in range(12):
        state = random_state(
            rng, net, n_pass=int(rng.integers(1, 6)), n_vac=int(rng.integers(1, 4)), n_occ=int(rng.integers(0, 2))
        )
        rm = make_strategy("rtv").build(state)
        sol = solve(rm.model)
        assert rm.model.violations(sol.chosen) == []
        assert sol.objective >= greedy(rm.model) - 1e-9
        assert sol.objective == pytest.approx(brute_force(rm.model), abs=1e-6)


def test_r4_without_pairs_rtv_is_a_bipartite_assignment(solve):
    # On a star, passengers leaf i -> leaf 5+i (origins and destinations disjoint): with D̄ = 500 m no two
    # can share, since any pooling detours somebody by >= 1000 m.
    rng = np.random.default_rng(1)
    net = star(leaves=10)
    params = Params(max_detour_m=500.0)
    for _ in range(8):
        origins = rng.choice(np.arange(1, 6), size=4, replace=False)
        dests = rng.choice(np.arange(6, 11), size=4, replace=False)
        vac = [(int(rng.integers(0, 11)), float(rng.uniform(0, 100))) for _ in range(3)]
        state = round_state(net, list(zip(origins.tolist(), dests.tolist(), strict=True)), vac, params=params)
        rm = make_strategy("rtv").build(state)
        assert not (rm.kind == Kind.TRIP2).any()
        value = np.full((state.n_passengers, state.n_v0), -1e12)
        single = rm.model.col_request2 < 0
        value[rm.model.col_request1[single], rm.model.col_vehicle[single]] = rm.model.values[single]
        rows, cols = linear_sum_assignment(value, maximize=True)
        lsa = value[rows, cols][value[rows, cols] > -1e11].sum()
        assert solve(rm.model).objective == pytest.approx(lsa, abs=1e-6)


def test_r5_large_c_ko_serves_as_many_as_possible(solve):
    rng = np.random.default_rng(2)
    net = grid()
    for _ in range(8):
        state = random_state(rng, net, n_pass=5, n_vac=2)
        rm = make_strategy("rtv", c_ko="large").build(state)
        sol = solve(rm.model)
        served = sum(1 + int(rm.model.col_request2[c] >= 0) for c in sol.chosen)
        assert served == brute_force(rm.model, max_served=True)


def _rr_edge(state, a: int, b: int) -> bool:
    from rpbench.geometry import pool

    p = state.params
    fwd = pool(
        state.dist,
        state.p_origin[a],
        state.p_destination[a],
        state.p_origin[b],
        state.p_destination[b],
        max_pickup_m=p.max_pickup_m,
        max_detour_m=p.max_detour_m,
    )
    bwd = pool(
        state.dist,
        state.p_origin[b],
        state.p_destination[b],
        state.p_origin[a],
        state.p_destination[a],
        max_pickup_m=p.max_pickup_m,
        max_detour_m=p.max_detour_m,
    )
    return bool(fwd.feasible or bwd.feasible)


def test_r6_request_edges_are_necessary_for_pair_trips():
    net = grid()
    for seed, params in [(3, Params()), (3, Params(max_detour_m=1e-3))]:
        state = random_state(np.random.default_rng(seed), net, n_pass=6, n_vac=3, params=params)
        rm = make_strategy("rtv").build(state)
        pairs = np.flatnonzero(rm.kind == Kind.TRIP2)
        edges = {(a, b) for a in range(6) for b in range(a + 1, 6) if _rr_edge(state, a, b)}
        assert {(int(rm.model.col_request1[c]), int(rm.model.col_request2[c])) for c in pairs} <= edges
        if not edges:
            assert len(pairs) == 0
        else:
            assert len(pairs) > 0


def test_r8_empty_pool_or_fleet():
    net = grid()
    empty = make_strategy("rtv").build(round_state(net, [], [(0, 0.0)]))
    assert empty.model.n_cols == 0
    no_vehicles = make_strategy("rtv").build(round_state(net, [(0, 5), (1, 6)], []))
    assert no_vehicles.model.n_cols == 0


def test_r9_deterministic_model():
    net = grid()
    a = make_strategy("rtv").build(random_state(np.random.default_rng(4), net, 5, 3, 1))
    b = make_strategy("rtv").build(random_state(np.random.default_rng(4), net, 5, 3, 1))
    for name in ("col_vehicle", "col_request1", "col_request2", "values"):
        assert np.array_equal(getattr(a.model, name), getattr(b.model, name))


def test_pair_trip_value_counts_two_services(solve):
    # Two requests from the same corner to the same corner: one vehicle carrying both beats two vehicles.
    net = grid()
    state = round_state(net, [(0, 15), (0, 15)], [(1, 0.0), (4, 0.0)])
    rm = make_strategy("rtv").build(state)
    sol = solve(rm.model)
    assert [int(rm.kind[c]) for c in sol.chosen] == [Kind.TRIP2]
    trip = sol.chosen[0]
    # value = 2 c_ko + e - pk1 with e = l + l - l (identical trips) and pk1 = 400 m
    l_solo = state.p_solo_m[0]
    assert rm.utility_m[trip] == pytest.approx(2 * 3000 + l_solo - 400.0)


def test_rv_top_k_prunes_single_edges():
    rng = np.random.default_rng(5)
    state = random_state(rng, grid(), n_pass=4, n_vac=4)
    full = make_strategy("rtv").build(state)
    pruned = make_strategy("rtv", rv_top_k=1).build(state)
    singles = pruned.model.col_request2 < 0
    assert np.bincount(pruned.model.col_request1[singles]).max() <= 1
    assert pruned.model.n_cols <= full.model.n_cols


def test_r7_rebalancing_moves_min_idle_unserved_at_minimum_distance(solve):
    rng = np.random.default_rng(6)
    net = grid()
    for n_pass, n_vac in [(6, 2), (3, 5), (5, 5)]:
        state = random_state(
            rng, net, n_pass=n_pass, n_vac=n_vac, params=Params(max_pickup_m=500.0)
        )  # a short R̄ leaves requests unassigned
        strategy = make_strategy("rtv", rebalance=True)
        rm = strategy.build(state)
        chosen = solve(rm.model).chosen if rm.model.n_cols else np.zeros(0, np.int64)
        vehicles, targets = strategy.reposition(state, rm, chosen)
        served = np.isin(state.p_order, np.concatenate([rm.first[chosen], rm.second[chosen]]))
        idle = ~np.isin(state.v0_vehicle, rm.vehicle[chosen])
        assert len(vehicles) == min(int(idle.sum()), int((~served).sum()))
        assert len(set(vehicles.tolist())) == len(vehicles)
        # minimum total distance, by brute force over assignments of idle vehicles to unserved origins
        idle_v = np.flatnonzero(idle)
        unserved = np.flatnonzero(~served)
        cost = (
            state.v0_pre_m[idle_v][:, None]
            + state.dist[state.v0_node[idle_v][:, None], state.p_origin[unserved][None, :]]
        )
        k = len(vehicles)
        best = (
            min(
                sum(cost[i, j] for i, j in zip(rows, cols, strict=True))
                for rows in itertools.permutations(range(len(idle_v)), k)
                for cols in itertools.combinations(range(len(unserved)), k)
            )
            if k
            else 0.0
        )
        got = sum(
            state.v0_pre_m[np.flatnonzero(state.v0_vehicle == v)[0]]
            + state.dist[state.v0_node[np.flatnonzero(state.v0_vehicle == v)[0]], node]
            for v, node in zip(vehicles, targets, strict=True)
        )
        assert got == pytest.approx(best, abs=1e-6)
    assert not make_strategy("rtv").reposition(state, rm, chosen)[0].size  # off by default


def test_reassign_is_refused():
    from rpbench.exceptions import ParameterError

    with pytest.raises(ParameterError, match="reassign is not supported"):
        make_strategy("rtv", reassign=True)


def _plain_pair_trips(self, state, vac, c_ko: float, cols: dict) -> None:
    """RTV's size-2 trips the plain way: POOL on every pair of passengers, every vacant vehicle tried."""
    from rpbench.geometry import pool

    n = state.n_passengers
    if n < 2 or len(vac.p) == 0:
        return
    i, j = np.triu_indices(n, k=1)
    rr_pickup = state.params.max_pickup_m if self.options.rr_pickup_check else np.inf
    kw = dict(max_pickup_m=rr_pickup, max_detour_m=state.params.max_detour_m, order_rule=self.options.order_rule)
    fwd = pool(state.dist, state.p_origin[i], state.p_destination[i], state.p_origin[j], state.p_destination[j], **kw)
    bwd = pool(state.dist, state.p_origin[j], state.p_destination[j], state.p_origin[i], state.p_destination[i], **kw)
    edge = fwd.feasible | bwd.feasible
    i, j = i[edge], j[edge]
    pk = np.full((n, state.n_v0), np.inf)
    pk[vac.p, vac.v] = vac.pickup_m
    e, v = np.nonzero(np.isfinite(pk[i]) & np.isfinite(pk[j]))
    val_f = np.where(fwd.feasible[edge][e], 2 * c_ko + self._net(fwd.saving[edge][e], pk[i[e], v]), -np.inf)
    val_b = np.where(bwd.feasible[edge][e], 2 * c_ko + self._net(bwd.saving[edge][e], pk[j[e], v]), -np.inf)
    take_f = val_f >= val_b
    cols["kind"].append(np.full(len(e), Kind.TRIP2))
    cols["vehicle_row"].append(v)
    cols["r1"].append(i[e])
    cols["r2"].append(j[e])
    cols["first"].append(np.where(take_f, i[e], j[e]))
    cols["fofo"].append(np.where(take_f, fwd.fofo[edge][e], bwd.fofo[edge][e]))
    cols["value"].append(np.where(take_f, val_f, val_b))
    cols["pickup"].append(np.where(take_f, pk[i[e], v], pk[j[e], v]))


@pytest.mark.parametrize("n_pass, n_vac, pickup", [(9, 3, 900.0), (14, 6, 1200.0), (20, 10, 700.0)])
def test_pair_trips_on_shared_vehicles_equal_those_of_the_plain_search(monkeypatch, n_pass, n_vac, pickup):
    # rtv asks POOL only about passenger pairs that share a reachable vacant vehicle; the model must be the
    # one of every pair on every vehicle, column for column.
    from rpbench.strategies.rtv import RTV

    pair_trips = 0
    for seed in range(12):
        rng = np.random.default_rng(seed)
        state = random_state(rng, grid(5), n_pass=n_pass, n_vac=n_vac, n_occ=2, params=Params(max_pickup_m=pickup))
        fast = make_strategy("rtv").build(state)
        with monkeypatch.context() as patch:
            patch.setattr(RTV, "_add_pair_trips", _plain_pair_trips)
            plain = make_strategy("rtv").build(state)
        for name in ("kind", "vehicle", "first", "second", "fofo", "utility_m", "pickup_m"):
            assert np.array_equal(getattr(fast, name), getattr(plain, name)), (seed, name)
        for name in ("values", "col_vehicle", "col_request1", "col_request2"):
            assert np.array_equal(getattr(fast.model, name), getattr(plain.model, name)), (seed, name)
        pair_trips += int((fast.kind == Kind.TRIP2).sum())
    assert pair_trips > 0
