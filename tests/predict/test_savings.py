"""Expected savings ē(t), ē(p), ē(s), ē(0,p) and the dispatcher-facing API (docs/algorithms.md §2.7, I7, I8)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rpbench.predict.fixed_point import evaluate
from rpbench.scenarios.base import Params

from .conftest import make_instance


@pytest.fixture(scope="module")
def solved():
    return make_instance(seed=21, size=6, n_od=30, rate_per_h=15, max_pickup_m=2000, max_detour_m=2000).solve()


def test_i7_convex_combinations(solved):
    model, pred = solved
    sp = model.space
    lo = np.full(sp.n_classes, np.inf)
    hi = np.full(sp.n_classes, -np.inf)
    for w in range(len(model.rates)):
        cls, e, _, _ = model.matching.seeker(w)
        if len(cls) == 0:
            assert pred.od.e_seeker[w] == 0
            continue
        np.minimum.at(lo, cls, e)
        np.maximum.at(hi, cls, e)
        if pred.od.p_seeker[w] > 0:  # ē(s) between min and max E over T_s
            assert e.min() - 1e-6 <= pred.od.e_seeker[w] <= e.max() + 1e-6
    c = sp.cls
    matched = np.isfinite(lo[c]) & (pred.eta > 0)
    assert np.all(pred.od.e_taker[matched] >= lo[c][matched] - 1e-6)
    assert np.all(pred.od.e_taker[matched] <= hi[c][matched] + 1e-6)
    assert np.all(pred.od.e_taker[~matched] == 0)
    off = sp.od_state_off
    for w in range(len(model.rates)):
        s = slice(off[w], off[w + 1])
        pi = pred.od.state_pair_prob[s]
        assert pi.sum() <= 1 + 1e-12 and np.all(pi >= 0)
        assert 0 <= pred.od.e_vacant[w] <= (pred.od.e_taker[s].max() if s.stop > s.start else 0) + 1e-9


def test_e_vacant_is_the_paper_eq9_form(solved):
    """ē(p) = Σ_t ē(t) p_t λ_t / ((1 - p_s) λ_w) (paper Eq. 9) where p_s < 1."""
    model, pred = solved
    sp, lam = model.space, model.rates.rate_per_s
    num = np.bincount(sp.od, weights=pred.od.e_taker * pred.p_taker * pred.lam_taker, minlength=len(lam))
    ok = (pred.od.p_seeker < 1) & (lam > 0)
    np.testing.assert_allclose(pred.od.e_vacant[ok], (num / ((1 - pred.od.p_seeker) * lam))[ok], rtol=1e-8)


def test_i8_waiting_saving(solved):
    model, pred = solved
    params = Params()
    o, d = model.rates.origin, model.rates.destination
    bracket = pred.od.p_seeker * pred.od.e_seeker + (1 - pred.od.p_seeker) * pred.od.e_vacant
    rounds = int(params.planner_patience_s // params.dt_s)  # 9 with the paper's K̄ = 90 s, Δt = 10 s
    values = [pred.e_wait(o, d, np.full(len(o), k), params) for k in range(1, rounds + 2)]
    for v in values:
        assert np.all(v >= 0) and np.all(v <= bracket + 1e-9)
    assert np.all(values[rounds - 1] == 0) and np.all(values[rounds] == 0)  # n_rem = 0
    assert all(np.all(a >= b - 1e-12) for a, b in itertools.pairwise(values))  # more rounds left, more saving
    low = pred.e_wait(o, d, 1, params.replace(response_rate=0.3))
    high = pred.e_wait(o, d, 1, params.replace(response_rate=0.9))
    assert np.all(high >= low)
    np.testing.assert_allclose(pred.e_wait(o, d, 1, params.replace(response_rate=1.0)), bracket)
    k1 = 1 - (1 - params.response_rate) ** (rounds - 1)
    np.testing.assert_allclose(values[0], k1 * bracket)


def test_lookup_known_and_unknown(solved):
    model, pred = solved
    r = model.rates
    o = np.concatenate([r.origin, [0]])
    d = np.concatenate([r.destination, [0]])  # (0, 0) is not in the table
    look = pred.lookup(o, d)
    assert look.known.tolist() == [True] * len(r) + [False]
    np.testing.assert_array_equal(look.e_vacant[:-1], pred.od.e_vacant)
    np.testing.assert_array_equal(look.p_seeker[:-1], pred.od.p_seeker)
    np.testing.assert_array_equal(look.e_seeker[:-1], pred.od.e_seeker)
    assert look.e_vacant[-1] == look.p_seeker[-1] == look.e_seeker[-1] == look.pairing_prob[-1] == 0
    assert pred.e_wait([0], [0], [1], Params())[0] == 0


def test_per_od_table_and_summary(solved):
    model, pred = solved
    table = pred.per_od_table()
    assert len(table) == len(model.rates)
    for col in (
        "matching_prob",
        "p_seeker",
        "e_vacant",
        "e_seeker",
        "ride_distance",
        "shared_distance",
        "detour_distance",
        "saved_distance_for_seeker",
        "saved_distance_for_taker",
    ):
        assert col in table and np.all(np.isfinite(table[col]))
    assert np.all(table["ride_distance"] >= table["solo_distance"] - 1e-6)  # detours are >= 0 (G1)
    assert np.all(table["shared_distance"] <= table["ride_distance"] + 1e-6)
    s = pred.summary()
    for key in ("ods", "states", "candidate_pairs", "iterations", "residual", "converged", "clip_count"):
        assert key in s
    assert s["converged"] is True and s["candidate_pairs"] >= s["class_pairs"] > 0


def test_expected_ride_matches_the_authors_decomposition(solved):
    """L_w = p_s R_s + (1 - p_s) [Σ π_k R_t(k) + (1 - Σπ) l_w] (TR-B; docs/algorithms.md §2.7)."""
    model, pred = solved
    od = pred.od
    expected = od.p_seeker * (od.solo_m + od.seeker_detour_m) + (1 - od.p_seeker) * od.taker_ride_m
    np.testing.assert_allclose(od.ride_m, expected)
    ev = evaluate(model.system, pred.rho)
    np.testing.assert_allclose(ev.p_seeker, od.p_seeker)
