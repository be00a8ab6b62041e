"""POOL(A, B, h, δ, pre) of rpbench.geometry on hand-written distance matrices.

Two small maps, every shortest distance written out by hand:

* ``LINE``: five nodes on a two-way street, 1 km apart (l(i, j) = 1000·|i - j|)::

      0 --- 1 --- 2 --- 3 --- 4

* ``SQUARE``: a 1 km square 0-1-2-3 whose side 0 -> 1 is one-way (so 1 -> 0 goes
  round the other three sides, 3 km)::

      0 ---> 1
      |      |
      3 ---- 2

Notation as in the module docstring: A owns the vehicle, B joins, p = l(h, o_B),
FOFO: L_F = δ + p + l(o_B, d_A) + l(d_A, d_B), FOLO: L_L = δ + p + l_B + l(d_B, d_A),
e = l_A + l_B - L.
"""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.exceptions import ParameterError
from rpbench.geometry import ORDER_RULES, TOLERANCE_M, choose_order, pair_geometry, pool

LINE = np.array(
    [
        #  0     1     2     3     4        (to)
        [0000, 1000, 2000, 3000, 4000],  # from 0
        [1000, 0000, 1000, 2000, 3000],  # from 1
        [2000, 1000, 0000, 1000, 2000],  # from 2
        [3000, 2000, 1000, 0000, 1000],  # from 3
        [4000, 3000, 2000, 1000, 0000],  # from 4
    ],
    dtype=float,
)

SQUARE = np.array(
    [
        #  0     1     2     3              (to)
        [0000, 1000, 2000, 1000],  # from 0: 0->1, 0->1->2 (or 0->3->2), 0->3
        [3000, 0000, 1000, 2000],  # from 1: 1->2->3->0 (no 1->0), 1->2, 1->2->3
        [2000, 1000, 0000, 1000],  # from 2: 2->3->0, 2->1, 2->3
        [1000, 2000, 1000, 0000],  # from 3: 3->0, 3->0->1 (or 3->2->1), 3->2
    ],
    dtype=float,
)

BIG = 1e9  # a threshold that never binds


def scalar(result, name):
    return float(np.asarray(getattr(result, name)))


def test_constants():
    assert TOLERANCE_M == 1e-9
    assert ORDER_RULES == ("min_feasible", "min_then_check")


def test_fofo_pair_on_a_line():
    # A: 0 -> 3 (l_A = 3000), B: 1 -> 4 (l_B = 3000), vehicle at o_A: h = 0, δ = 0, pre = 0.
    # p = l(0, 1) = 1000 = pick-up distance of B.
    # FOFO: L_F = 0 + 1000 + l(1, 3) 2000 + l(3, 4) 1000 = 4000
    #       ride_A = 1000 + 2000 = 3000 (detour 0), ride_B = 2000 + 1000 = 3000 (detour 0), shared = 2000
    # FOLO: L_L = 1000 + 3000 + l(4, 3) 1000 = 5000 -> ride_A = 5000 (detour 2000), ride_B = 3000
    # Both feasible at D̄ = 3000; FOFO is shorter: e = 3000 + 3000 - 4000 = 2000.
    g = pair_geometry(LINE, 0, 3, 3000.0, 1, 4, 3000.0, 0, 0.0, 0.0, max_detour_m=3000.0)
    assert float(g.p) == 1000 and float(g.pk) == 1000
    assert float(g.fofo_length) == 4000 and float(g.folo_length) == 5000
    assert float(g.l_oB_dA) == 2000 and float(g.l_dA_dB) == 1000
    assert bool(g.fofo_ok) and bool(g.folo_ok)

    r = pool(LINE, 0, 3, 1, 4, max_pickup_m=3000.0, max_detour_m=3000.0)
    assert bool(r.feasible) and bool(r.fofo)
    assert scalar(r, "length") == 4000
    assert scalar(r, "ride_a") == 3000 and scalar(r, "ride_b") == 3000
    assert scalar(r, "detour_a") == 0 and scalar(r, "detour_b") == 0
    assert scalar(r, "shared") == 2000
    assert scalar(r, "pk") == 1000
    assert scalar(r, "saving") == 2000


def test_folo_pair_on_a_line():
    # A: 0 -> 4 (l_A = 4000), B: 1 -> 3 (l_B = 2000), h = o_A = 0: p = 1000.
    # FOFO: L_F = 1000 + l(1, 4) 3000 + l(4, 3) 1000 = 5000
    #       detour_A = 1000 + 3000 - 4000 = 0, ride_B = 3000 + 1000 = 4000 -> detour_B = 2000
    # FOLO: L_L = 1000 + 2000 + l(3, 4) 1000 = 4000 -> detour_A = 0, ride_B = l_B (detour 0), shared = l_B = 2000
    # FOLO is shorter: e = 4000 + 2000 - 4000 = 2000.
    r = pool(LINE, 0, 4, 1, 3, max_pickup_m=3000.0, max_detour_m=3000.0)
    assert bool(r.feasible) and not bool(r.fofo)
    assert scalar(r, "length") == 4000
    assert scalar(r, "ride_a") == 4000 and scalar(r, "ride_b") == 2000
    assert scalar(r, "detour_a") == 0 and scalar(r, "detour_b") == 0
    assert scalar(r, "shared") == 2000
    assert scalar(r, "saving") == 2000

    # The rejected FOFO order, read off pair_geometry: B's detour 2000 m is fine at D̄ = 2000, not at 1999.
    g = pair_geometry(LINE, 0, 4, 4000.0, 1, 3, 2000.0, 0, 0.0, 0.0, max_detour_m=2000.0)
    assert float(g.fofo_length) == 5000 and float(g.folo_length) == 4000
    assert bool(g.fofo_ok) and bool(g.folo_ok)
    g = pair_geometry(LINE, 0, 4, 4000.0, 1, 3, 2000.0, 0, 0.0, 0.0, max_detour_m=1999.0)
    assert not bool(g.fofo_ok) and bool(g.folo_ok)


def test_negative_saving_pair():
    # A: 0 -> 1 (l_A = 1000), B: 2 -> 0 (l_B = 2000) — B stands beyond A's destination, going back.
    # p = l(0, 2) = 2000.
    # FOFO: L_F = 2000 + l(2, 1) 1000 + l(1, 0) 1000 = 4000
    #       ride_A = 2000 + 1000 = 3000 -> detour_A = 2000; ride_B = 1000 + 1000 = 2000 -> detour_B = 0
    #       shared = l(o_B, d_A) = 1000
    # FOLO: L_L = 2000 + 2000 + l(0, 1) 1000 = 5000 -> detour_A = 4000
    # e = 1000 + 2000 - 4000 = -1000: feasible pairs can lose distance.
    r = pool(LINE, 0, 1, 2, 0, max_pickup_m=3000.0, max_detour_m=3000.0)
    assert bool(r.feasible) and bool(r.fofo)
    assert scalar(r, "length") == 4000
    assert scalar(r, "detour_a") == 2000 and scalar(r, "detour_b") == 0
    assert scalar(r, "shared") == 1000
    assert scalar(r, "saving") == -1000


@pytest.mark.parametrize(
    "max_detour, fofo_ok, folo_ok",
    [
        (1999.999, False, False),  # A's FOFO detour 2000 > D̄
        (2000.0 - TOLERANCE_M / 2, True, False),  # inside the 1e-9 m tolerance
        (2000.0, True, False),  # inclusive
        (3999.0, True, False),  # FOLO detour of A is 4000
        (4000.0, True, True),
    ],
)
def test_detour_threshold_is_inclusive(max_detour, fofo_ok, folo_ok):
    # Same pair as test_negative_saving_pair: detour_A = 2000 (FOFO) and 4000 (FOLO), detour_B = 0 in both.
    g = pair_geometry(LINE, 0, 1, 1000.0, 2, 0, 2000.0, 0, 0.0, 0.0, max_detour_m=max_detour)
    assert bool(g.fofo_ok) is fofo_ok
    assert bool(g.folo_ok) is folo_ok
    r = pool(LINE, 0, 1, 2, 0, max_pickup_m=BIG, max_detour_m=max_detour)
    assert bool(r.feasible) is (fofo_ok or folo_ok)
    if fofo_ok:
        assert bool(r.fofo)  # 4000 < 5000 whenever FOFO is allowed


@pytest.mark.parametrize(
    "max_pickup, feasible",
    [
        (999.999, False),
        (1000.0 - TOLERANCE_M / 2, True),
        (1000.0, True),
        (1000.001, True),
    ],
)
def test_pickup_threshold_is_inclusive(max_pickup, feasible):
    # A: 0 -> 3, B: 1 -> 4 (test_fofo_pair_on_a_line): pk = pre + p = 0 + 1000.
    r = pool(LINE, 0, 3, 1, 4, max_pickup_m=max_pickup, max_detour_m=3000.0)
    assert bool(r.feasible) is feasible
    assert scalar(r, "pk") == 1000


def test_pickup_threshold_counts_pre():
    # Same pair, but the vehicle is still pre = 600 m before o_A: pk = 600 + 1000 = 1600.
    r = pool(LINE, 0, 3, 1, 4, h=0, delta=0.0, pre=600.0, max_pickup_m=1600.0, max_detour_m=3000.0)
    assert bool(r.feasible) and scalar(r, "pk") == 1600
    assert scalar(r, "length") == 4000  # pre is not part of L
    r = pool(LINE, 0, 3, 1, 4, h=0, delta=0.0, pre=600.0, max_pickup_m=1599.0, max_detour_m=3000.0)
    assert not bool(r.feasible)


def test_order_rules_differ_on_a_one_way_street():
    # SQUARE, A: 0 -> 1 (l_A = 1000), B: 2 -> 0 (l_B = l(2, 0) = 2000), h = o_A = 0: p = l(0, 2) = 2000.
    # FOFO: L_F = 2000 + l(2, 1) 1000 + l(1, 0) 3000 = 6000
    #       detour_A = 2000 + 1000 - 1000 = 2000, ride_B = 1000 + 3000 = 4000 -> detour_B = 2000
    # FOLO: L_L = 2000 + 2000 + l(0, 1) 1000 = 5000 -> detour_A = 5000 - 1000 = 4000
    # With D̄ = 2000 only FOFO is feasible, but FOLO is the shorter order:
    #   min_feasible takes FOFO (feasible, e = 1000 + 2000 - 6000 = -3000);
    #   min_then_check takes FOLO first, then finds it infeasible -> no pair.
    g = pair_geometry(SQUARE, 0, 1, 1000.0, 2, 0, 2000.0, 0, 0.0, 0.0, max_detour_m=2000.0)
    assert float(g.fofo_length) == 6000 and float(g.folo_length) == 5000
    assert bool(g.fofo_ok) and not bool(g.folo_ok)

    mf = choose_order(g, max_pickup_m=3000.0, order_rule="min_feasible")
    assert bool(mf.feasible) and bool(mf.fofo)
    assert scalar(mf, "length") == 6000
    assert scalar(mf, "detour_a") == 2000 and scalar(mf, "detour_b") == 2000
    assert scalar(mf, "shared") == 1000  # l(o_B, d_A) = l(2, 1)
    assert scalar(mf, "saving") == -3000

    mc = choose_order(g, max_pickup_m=3000.0, order_rule="min_then_check")
    assert not bool(mc.feasible) and not bool(mc.fofo)
    assert scalar(mc, "length") == 5000

    # pool() forwards the rule.
    assert bool(pool(SQUARE, 0, 1, 2, 0, max_pickup_m=3000.0, max_detour_m=2000.0).feasible)
    assert not bool(
        pool(SQUARE, 0, 1, 2, 0, max_pickup_m=3000.0, max_detour_m=2000.0, order_rule="min_then_check").feasible
    )
    # With D̄ = 4000 both orders are feasible and both rules agree on FOLO (e = 3000 - 5000 = -2000).
    for rule in ORDER_RULES:
        r = pool(SQUARE, 0, 1, 2, 0, max_pickup_m=3000.0, max_detour_m=4000.0, order_rule=rule)
        assert bool(r.feasible) and not bool(r.fofo) and scalar(r, "saving") == -2000


def test_unknown_order_rule():
    g = pair_geometry(LINE, 0, 3, 3000.0, 1, 4, 3000.0, 0, 0.0, 0.0, max_detour_m=3000.0)
    with pytest.raises(ParameterError, match="order_rule"):
        choose_order(g, max_pickup_m=3000.0, order_rule="shortest")


def test_tie_goes_to_fofo():
    # A: 0 -> 2 (2000), B: 1 -> 0 (1000), p = 1000.
    # FOFO: L_F = 1000 + l(1, 2) 1000 + l(2, 0) 2000 = 4000 (detour_A 0, ride_B 3000 -> detour_B 2000)
    # FOLO: L_L = 1000 + 1000 + l(0, 2) 2000 = 4000 (detour_A 2000, detour_B 0)
    for rule in ORDER_RULES:
        r = pool(LINE, 0, 2, 1, 0, max_pickup_m=3000.0, max_detour_m=3000.0, order_rule=rule)
        assert bool(r.feasible) and bool(r.fofo)
        assert scalar(r, "length") == 4000
        assert scalar(r, "detour_a") == 0 and scalar(r, "detour_b") == 2000
        assert scalar(r, "saving") == -1000  # 2000 + 1000 - 4000


def test_en_route_ahead():
    # The vehicle carries A (0 -> 4, l_A = 4000) and is pre = 400 m before h = 1; at h A has ridden δ = 1000.
    # B: 2 -> 3 (l_B = 1000): p = l(1, 2) = 1000, pk = 400 + 1000 = 1400.
    # FOFO: L_F = 1000 + 1000 + l(2, 4) 2000 + l(4, 3) 1000 = 5000
    #       ride_A = 1000 + 1000 + 2000 = 4000 (detour 0), ride_B = 2000 + 1000 = 3000 (detour 2000)
    # FOLO: L_L = 1000 + 1000 + 1000 + l(3, 4) 1000 = 4000 -> ride_A = 4000 (detour 0), ride_B = 1000, shared 1000
    # e = 4000 + 1000 - 4000 = 1000.
    g = pair_geometry(LINE, 0, 4, 4000.0, 2, 3, 1000.0, 1, 1000.0, 400.0, max_detour_m=3000.0)
    assert float(g.p) == 1000 and float(g.pk) == 1400
    assert float(g.fofo_length) == 5000 and float(g.folo_length) == 4000

    r = pool(LINE, 0, 4, 2, 3, h=1, delta=1000.0, pre=400.0, max_pickup_m=3000.0, max_detour_m=3000.0)
    assert bool(r.feasible) and not bool(r.fofo)
    assert scalar(r, "pk") == 1400
    assert scalar(r, "length") == 4000
    assert scalar(r, "ride_a") == 4000 and scalar(r, "ride_b") == 1000
    assert scalar(r, "detour_a") == 0 and scalar(r, "detour_b") == 0
    assert scalar(r, "shared") == 1000
    assert scalar(r, "saving") == 1000
    # R̄ binds on pre + p = 1400, not on p alone.
    assert bool(pool(LINE, 0, 4, 2, 3, h=1, delta=1000.0, pre=400.0, max_pickup_m=1400.0, max_detour_m=3000.0).feasible)
    assert not bool(
        pool(LINE, 0, 4, 2, 3, h=1, delta=1000.0, pre=400.0, max_pickup_m=1399.0, max_detour_m=3000.0).feasible
    )


def test_en_route_turning_back():
    # The vehicle carries A (0 -> 4) and is 300 m before h = 2 (δ = 2000); B waits behind it: 1 -> 3 (l_B = 2000).
    # p = l(2, 1) = 1000, pk = 300 + 1000 = 1300.
    # FOFO: L_F = 2000 + 1000 + l(1, 4) 3000 + l(4, 3) 1000 = 7000
    #       ride_A = 2000 + 1000 + 3000 = 6000 -> detour_A = 2000; ride_B = 3000 + 1000 = 4000 -> detour_B = 2000
    # FOLO: L_L = 2000 + 1000 + 2000 + l(3, 4) 1000 = 6000 -> detour_A = 2000, detour_B = 0, shared = 2000
    # FOLO is shorter: e = 4000 + 2000 - 6000 = 0.
    r = pool(LINE, 0, 4, 1, 3, h=2, delta=2000.0, pre=300.0, max_pickup_m=3000.0, max_detour_m=3000.0)
    assert bool(r.feasible) and not bool(r.fofo)
    assert scalar(r, "pk") == 1300
    assert scalar(r, "length") == 6000
    assert scalar(r, "ride_a") == 6000 and scalar(r, "ride_b") == 2000
    assert scalar(r, "detour_a") == 2000 and scalar(r, "detour_b") == 0
    assert scalar(r, "shared") == 2000
    assert scalar(r, "saving") == 0
    # Both orders detour A by 2000 m: at D̄ = 1999 neither is feasible.
    assert not bool(
        pool(LINE, 0, 4, 1, 3, h=2, delta=2000.0, pre=300.0, max_pickup_m=3000.0, max_detour_m=1999.0).feasible
    )


def test_vectorised_matches_single_pairs():
    # The pairs above as one batch (h defaults to o_A).
    o_a, d_a, o_b, d_b = [0, 0, 0, 0], [3, 4, 1, 2], [1, 1, 2, 1], [4, 3, 0, 0]
    r = pool(LINE, o_a, d_a, o_b, d_b, max_pickup_m=3000.0, max_detour_m=3000.0)
    np.testing.assert_array_equal(r.feasible, [True, True, True, True])
    np.testing.assert_array_equal(r.fofo, [True, False, True, True])
    np.testing.assert_array_equal(r.length, [4000, 4000, 4000, 4000])
    np.testing.assert_array_equal(r.saving, [2000, 2000, -1000, -1000])
    np.testing.assert_array_equal(r.shared, [2000, 2000, 1000, 1000])
    np.testing.assert_array_equal(r.pk, [1000, 1000, 2000, 1000])
