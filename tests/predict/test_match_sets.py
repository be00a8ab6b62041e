"""Matching sets, savings and priority order vs a brute-force POOL over every (seeker, state) pair."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rpbench.data.road import NetworkTables
from rpbench.geometry import pool
from rpbench.network import RoadNetwork
from rpbench.predict import OdRates, PredictConfig, build_prediction_model
from rpbench.predict.match_sets import GRID
from rpbench.scenarios.base import Params

from .conftest import make_instance

AMBIGUOUS_M = 1e-6  # |E| this small: rounding decides whether E > 0 (the model computes E = 0 exactly)


def brute_force(model, w):
    """Expected state list of seeker w: feasible POOL pairs, sorted by the documented priority rule."""
    sp, r, cfg = model.space, model.rates, model.config
    dist = model.network.distances().dist
    t = np.arange(sp.n_states)
    res = pool(
        dist,
        r.origin[sp.od],
        r.destination[sp.od],
        np.full(len(t), r.origin[w]),
        np.full(len(t), r.destination[w]),
        h=sp.head,
        delta=sp.delta_m,
        pre=sp.pre_m,
        max_pickup_m=model.params.max_pickup_m,
        max_detour_m=model.params.max_detour_m,
        order_rule=cfg.order_rule,
    )
    ok = res.feasible if cfg.keep_nonpositive else res.feasible & (res.saving > 0)
    # |E| this small: rounding decides its sign (and, kept, its place) while the model computes E = 0.
    ambiguous = set(t[res.feasible & (np.abs(res.saving) <= AMBIGUOUS_M)].tolist())
    idx = t[ok]
    e, pk = res.saving[ok], res.pk[ok]
    prio = {"net_saving": e - pk, "pickup": -pk, "fl_utility": np.where(e > 0, e * e / np.maximum(e + pk, 1e-300), e)}[
        cfg.priority
    ]
    order = np.lexsort((sp.k[idx], sp.od[idx], sp.cls[idx], np.floor(pk * GRID), np.floor(-prio * GRID)))
    distances = np.stack([e, res.shared[ok], res.detour_b[ok]])[:, order]  # E, shared, seeker detour
    return idx[order], distances, ambiguous, res


def model_list(model, w):
    """Seeker w's taker states in list order, and their (E, shared, seeker detour)."""
    cls, e, sh, det = model.matching.seeker(w)
    sp = model.space
    states = (
        np.concatenate([sp.class_members[sp.class_off[c] : sp.class_off[c + 1]] for c in cls])
        if len(cls)
        else np.zeros(0, dtype=np.int64)
    )
    return states, np.repeat(np.stack([e, sh, det]), sp.class_size[cls], axis=1)


def check_against_brute_force(model):
    for w in range(len(model.rates)):
        expected, e_exp, ambiguous, _ = brute_force(model, w)
        got, e_got = model_list(model, w)
        # The simulator never pools a zero-length order (its E <= 0, up to rounding), while the prediction
        # still lists its pairs (docs/simulator.md, zero-length orders): they are left out of the comparison.
        sp, r = model.space, model.rates
        zero = r.origin == r.destination
        if zero[w]:
            continue
        kept = ~zero[sp.od[got]]
        got, e_got = got[kept], e_got[:, kept]
        if model.config.keep_nonpositive:  # feasibility does not depend on the sign of E
            assert ambiguous <= set(got.tolist()) and ambiguous <= set(expected.tolist())
        if ambiguous:
            got_keep, exp_keep = ~np.isin(got, list(ambiguous)), ~np.isin(expected, list(ambiguous))
            got, e_got, expected, e_exp = got[got_keep], e_got[:, got_keep], expected[exp_keep], e_exp[:, exp_keep]
        assert got.tolist() == expected.tolist(), f"seeker {w}"
        np.testing.assert_allclose(e_got, e_exp, rtol=1e-6, atol=1e-3)  # float32 values


@settings(max_examples=15, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    pickup=st.sampled_from([400.0, 900.0, 2000.0]),
    detour=st.sampled_from([0.0, 300.0, 1500.0]),
    rule=st.sampled_from(["min_feasible", "min_then_check"]),
    keep=st.booleans(),
    priority=st.sampled_from(["net_saving", "pickup", "fl_utility"]),
    origin_state=st.booleans(),
)
def test_matching_equals_brute_force_pool(seed, pickup, detour, rule, keep, priority, origin_state):
    inst = make_instance(seed=seed, size=4, n_od=9, max_pickup_m=pickup, max_detour_m=max(detour, 1e-3))
    model = inst.model(order_rule=rule, keep_nonpositive=keep, priority=priority, include_origin_state=origin_state)
    check_against_brute_force(model)


def test_savings_bounded_by_solo_distances():  # I9 / G2
    model = make_instance(seed=11, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000).model()
    sp = model.space
    for w in range(len(model.rates)):
        cls, e, sh, det = model.matching.seeker(w)
        if len(cls) == 0:
            continue
        l_s = sp.solo_m[w]
        l_t = sp.class_rest_m[cls]  # the taker's remaining solo distance; l_t >= it
        assert np.all(e > 0)
        assert np.all(e <= np.minimum(l_s, l_t) * (1 + 1e-6) + 1e-3)
        assert np.all(det >= -1e-3) and np.all(det <= 1500 + 1e-3 + 3000)
        assert np.all(sh >= -1e-3)


def state_pairs(model):
    out = set()
    for w in range(len(model.rates)):
        states, _ = model_list(model, w)
        out.update((w, int(s)) for s in states)
    return out


def test_monotone_feasible_sets():  # L7
    base = make_instance(seed=5, size=5, n_od=15, max_pickup_m=600, max_detour_m=400, keep_nonpositive=True)
    small = state_pairs(base.model())
    for params in (dict(max_pickup_m=1200, max_detour_m=400), dict(max_pickup_m=600, max_detour_m=1200)):
        bigger = make_instance(seed=5, size=5, n_od=15, keep_nonpositive=True, **params)
        assert small <= state_pairs(bigger.model())


def line_network(lengths):
    n = len(lengths) + 1
    a, b = np.arange(n - 1), np.arange(1, n)
    lengths = np.asarray(lengths, dtype=float)
    tables = NetworkTables(
        name="line",
        node_id=np.arange(n),
        lon=110 + np.arange(n) * 1e-3,
        lat=np.full(n, 20.0),
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.concatenate([lengths, lengths]),
        arc_link_id=np.concatenate([np.arange(n - 1)] * 2),
        source="test",
    )
    return RoadNetwork.from_tables(tables)


@pytest.mark.parametrize("pickup, expected", [(1000.0, True), (1000.0 - 1e-6, False)])
def test_pickup_threshold_is_inclusive(pickup, expected):
    # Taker 0 -> 3 waits at node 0 (k = 0); the seeker 1 -> 3 is exactly 1000 m away.
    net = line_network([1000.0, 1000.0, 1000.0])
    rates = OdRates.from_arrays([0, 1], [3, 3], [1e-3, 1e-3], n_nodes=4)
    model = build_prediction_model(net, rates, Params(max_pickup_m=pickup, max_detour_m=3000), PredictConfig())
    w_seeker = 1  # canonical order: (0,3), (1,3)
    states, _ = model_list(model, w_seeker)
    origin_state_of_taker = model.space.od_state_off[0]
    assert (origin_state_of_taker in states) is expected


def test_chunks_partition_the_seekers():
    model = make_instance(seed=2, size=6, n_od=60, max_pickup_m=3000, max_detour_m=3000).model()
    m = model.matching
    for max_pairs in (1, 7, 50, 10**9):
        chunks = list(m.chunks(max_pairs))
        assert chunks[0][0] == 0 and chunks[-1][1] == len(model.rates)
        for (_, s1, _, i1), (s0, _, i0, _) in itertools.pairwise(chunks):
            assert s1 == s0 and i1 == i0
        assert all(s1 == s0 + 1 or i1 - i0 <= max_pairs for s0, s1, i0, i1 in chunks)
    cls, e, _, _ = m.arrays()
    assert len(cls) == m.n_pairs == m.seeker_off[-1]
    for w in (0, 17, 59):
        np.testing.assert_array_equal(m.seeker(w)[0], cls[m.seeker_off[w] : m.seeker_off[w + 1]])


@pytest.mark.parametrize("priority", ["net_saving", "pickup"])
def test_lexsort_fallback_gives_the_same_lists(monkeypatch, priority):
    # Priorities beyond the packed key's range take the lexsort route; the lists must not change.
    inst = make_instance(seed=4, size=5, n_od=25, max_pickup_m=2000, max_detour_m=2000)
    packed = inst.model(priority=priority).matching.arrays()
    monkeypatch.setattr("rpbench.predict.match_sets._Q_LIMIT", 1e-9)
    model = build_prediction_model(
        inst.network, inst.rates, inst.params, inst.config.replace(priority=priority), use_cache=False
    )  # a private build: the cached one is packed
    for got, want in zip(model.matching.arrays(), packed, strict=True):
        np.testing.assert_array_equal(got, want)
    check_against_brute_force(model)


def test_recorded_state_pair_count_equals_a_direct_count():
    model = make_instance(seed=8, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000).model()
    m, sp = model.matching, model.space
    direct = int(sp.class_size[m.cls].sum())
    assert m.stats["state_pairs"] == direct == m.count_state_pairs(sp.class_size) == m.n_state_pairs(sp)
