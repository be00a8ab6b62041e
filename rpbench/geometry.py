"""The pair primitive POOL(A, B, h, δ, pre) of docs/algorithms.md §1.1 (paper Eqs. 5-6).

``A`` owns the vehicle (on board or assigned), ``B`` joins.  The vehicle can
divert towards ``o_B`` at node ``h``, which lies on A's shortest path after A
has ridden ``δ`` metres of it; ``pre`` is what the vehicle still drives
before reaching ``h`` (it only enters the pick-up distance).  Two service
orders exist::

    FOFO (A dropped first): L_F = δ + p + l(o_B,d_A) + l(d_A,d_B)
    FOLO (A dropped last):  L_L = δ + p + l_B + l(d_B,d_A)        with p = l(h, o_B)

An order is feasible when both detours are <= D̄; the pair is feasible when
``pk = pre + p <= R̄`` and some order is feasible.  The chosen order is the
feasible one with the smaller L (tie -> FOFO; ``order_rule="min_then_check"``
instead picks the smaller L first and then tests it, as the authors' code
did).  The saving is ``e = l_A + l_B - L_chosen``.  Thresholds are inclusive
with a 1e-9 m tolerance (A23).  A pair with a zero-length order (origin and destination on one node,
``l = 0``) is never feasible: by the triangle inequality its saving is at most 0, so such an order is
served solo.

Everything is vectorised: inputs are broadcastable arrays of node indices
and distances, ``dist`` is the all-pairs matrix of the one distance oracle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rpbench.exceptions import ParameterError

TOLERANCE_M = 1e-9
ORDER_RULES = ("min_feasible", "min_then_check")


@dataclass(frozen=True)
class PairGeometry:
    """Both service orders of a batch of (A, B) pairs; every field is an array."""

    p: np.ndarray  # l(h, o_B)
    pk: np.ndarray  # pre + p, the pick-up distance of B
    fofo_length: np.ndarray
    folo_length: np.ndarray
    fofo_ok: np.ndarray  # both detours within D̄ in FOFO
    folo_ok: np.ndarray
    l_oB_dA: np.ndarray  # shared distance of FOFO
    l_dA_dB: np.ndarray
    delta: np.ndarray
    l_a: np.ndarray
    l_b: np.ndarray


@dataclass(frozen=True)
class PoolResult:
    """The chosen service order of each pair (arrays; undefined where not ``feasible``)."""

    feasible: np.ndarray  # bool
    fofo: np.ndarray  # bool: True = A dropped first
    length: np.ndarray  # L of the chosen order (from A's origin)
    ride_a: np.ndarray
    ride_b: np.ndarray
    shared: np.ndarray
    detour_a: np.ndarray
    detour_b: np.ndarray
    pk: np.ndarray
    saving: np.ndarray  # e(A, B) = l_A + l_B - L


def pair_geometry(dist: np.ndarray, o_a, d_a, l_a, o_b, d_b, l_b, h, delta, pre, max_detour_m: float) -> PairGeometry:
    """Distances and detour feasibility of both service orders."""
    o_a, d_a, o_b, d_b, h = (np.asarray(x, dtype=np.intp) for x in (o_a, d_a, o_b, d_b, h))
    l_a, l_b, delta, pre = (np.asarray(x, dtype=np.float64) for x in (l_a, l_b, delta, pre))
    p = dist[h, o_b]
    l_oB_dA = dist[o_b, d_a]
    l_dA_dB = dist[d_a, d_b]
    l_dB_dA = dist[d_b, d_a]
    head = delta + p
    fofo_length = head + l_oB_dA + l_dA_dB
    folo_length = head + l_b + l_dB_dA
    lim = max_detour_m + TOLERANCE_M
    fofo_ok = (head + l_oB_dA - l_a <= lim) & (l_oB_dA + l_dA_dB - l_b <= lim)
    folo_ok = folo_length - l_a <= lim  # B rides solo in FOLO: detour_B = 0
    return PairGeometry(
        p=p,
        pk=pre + p,
        fofo_length=fofo_length,
        folo_length=folo_length,
        fofo_ok=fofo_ok,
        folo_ok=folo_ok,
        l_oB_dA=l_oB_dA,
        l_dA_dB=l_dA_dB,
        delta=delta,
        l_a=l_a,
        l_b=l_b,
    )


def choose_order(g: PairGeometry, max_pickup_m: float, order_rule: str = "min_feasible") -> PoolResult:
    """Pick each pair's service order and derive rides, detours and the saving."""
    if order_rule == "min_feasible":
        fofo = g.fofo_ok & (~g.folo_ok | (g.fofo_length <= g.folo_length))
        ok = g.fofo_ok | g.folo_ok
    elif order_rule == "min_then_check":
        fofo = g.fofo_length <= g.folo_length
        ok = np.where(fofo, g.fofo_ok, g.folo_ok)
    else:
        raise ParameterError(f"order_rule {order_rule!r} unknown; expected one of {', '.join(ORDER_RULES)}")
    # A zero-length trip (origin = destination node) is served solo, never pooled: it can only lose (e <= 0).
    feasible = ok & (g.pk <= max_pickup_m + TOLERANCE_M) & (g.l_a > TOLERANCE_M) & (g.l_b > TOLERANCE_M)
    length = np.where(fofo, g.fofo_length, g.folo_length)
    ride_a = np.where(fofo, g.delta + g.p + g.l_oB_dA, length)
    ride_b = np.where(fofo, g.l_oB_dA + g.l_dA_dB, g.l_b)
    shared = np.where(fofo, g.l_oB_dA, g.l_b)
    return PoolResult(
        feasible=feasible,
        fofo=fofo,
        length=length,
        ride_a=ride_a,
        ride_b=ride_b,
        shared=shared,
        detour_a=ride_a - g.l_a,
        detour_b=ride_b - g.l_b,
        pk=g.pk,
        saving=g.l_a + g.l_b - length,
    )


def pool(
    dist: np.ndarray,
    o_a,
    d_a,
    o_b,
    d_b,
    *,
    h=None,
    delta=0.0,
    pre=0.0,
    max_pickup_m: float,
    max_detour_m: float,
    order_rule: str = "min_feasible",
) -> PoolResult:
    """POOL(A, B, h, δ, pre) for arrays of pairs; ``h`` defaults to ``o_A`` (δ = 0)."""
    o_a = np.asarray(o_a, dtype=np.intp)
    d_a = np.asarray(d_a, dtype=np.intp)
    o_b = np.asarray(o_b, dtype=np.intp)
    d_b = np.asarray(d_b, dtype=np.intp)
    h = o_a if h is None else h
    g = pair_geometry(dist, o_a, d_a, dist[o_a, d_a], o_b, d_b, dist[o_b, d_b], h, delta, pre, max_detour_m)
    return choose_order(g, max_pickup_m, order_rule)
