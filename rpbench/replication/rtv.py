"""RTV under the authors' semantics: one round's trips and their values (their ``generate_RV_graph``,
``generate_RTV_graph`` and ``optimal_assignment``, re-implemented as an rpbench TripPackingModel).

Trips per free vehicle:

* a vacant vehicle: one-request trips to every passenger within the pick-up
  radius (value 3000 - pick-up, as MB's), and two-request trips for every
  pair of such passengers that can share (both detours within D).  The
  authors value a two-request trip at the pair's *saving alone* (no 3000 per
  request), so two vehicles serving the pair separately are usually worth
  more; rpbench's RTV values a trip c_ko |T| + e - pk (c_ko = R);
* a taker: one-request trips (value 3000 + saving - pick-up) to passengers
  passing the pick-up and detour tests from the vehicle's position *and* from
  the first passenger's origin.

No grid cells (their RTV does not use them); no keep-waiting value (an
unmatched passenger is worth 0); the authors' tests are strict (``<``), and
there is no pick-up test between the two requests of a trip.
"""

from __future__ import annotations

import numpy as np

from rpbench.model import TripPackingModel, quantize
from rpbench.replication.weights import AUTHORS_BONUS


def pair_legs(
    dist: np.ndarray, o: np.ndarray, d: np.ndarray, solo: np.ndarray, first: int, second: int, strict_ties: bool
) -> tuple[bool, float, float, float]:
    """Drop-off order of ``second`` joining ``first`` from O_second: (first-on-first-off?, shared, rest, ...).

    Returns (fofo, leg1, leg2, shared) with the authors' rule: FOFO iff its two legs sum strictly less.
    """
    f1, f2 = dist[o[second], d[first]], dist[d[first], d[second]]
    l1, l2 = solo[second], dist[d[second], d[first]]
    fofo = (f1 + f2 < l1 + l2) if strict_ties else (f1 + f2 <= l1 + l2)
    return (True, f1, f2, f1) if fofo else (False, l1, l2, l1)


def pair_geometry(dist, o, d, solo, first: int, second: int, lead_m: float, strict_ties: bool) -> dict[str, float]:
    """Rides, shared distance, saving and detours of ``first`` (in the vehicle ``lead_m`` before O_second)
    and ``second``."""
    fofo, leg1, leg2, shared = pair_legs(dist, o, d, solo, first, second, strict_ties)
    a_in = lead_m + leg1 if fofo else lead_m + leg1 + leg2
    b_in = leg1 + leg2 if fofo else leg1
    saving = solo[first] + solo[second] - (a_in + b_in - shared)
    return {
        "fofo": fofo,
        "a_in": a_in,
        "b_in": b_in,
        "shared": shared,
        "saving": saving,
        "detour_a": a_in - solo[first],
        "detour_b": b_in - solo[second],
        "rest": leg1 + leg2,
    }


def _within(x: float, limit: float, strict: bool) -> bool:
    return x < limit if strict else x <= limit


def build_round(engine, t: float, seekers: list[int], active: list[int]) -> tuple[TripPackingModel, list]:
    """The round's trip-packing model and, per column, (vehicle index, request tuple)."""
    sw, p = engine.sw, engine.sc.params
    dist, o, d, solo = engine.dist.dist, engine.o, engine.d, engine.solo
    strict = sw.authors_weights
    authors = sw.authors_weights
    s = list(seekers)
    pos = {r: i for i, r in enumerate(s)}
    cols: list[tuple[int, tuple[int, ...]]] = []
    values: list[float] = []
    # Request-request edges: first = the later-listed passenger (the authors' loop order), pick-up from its origin.
    rr: dict[tuple[int, int], float] = {}
    for i in range(len(s)):
        for j in range(i + 1, len(s)):
            first, second = s[j], s[i]
            g = pair_geometry(dist, o, d, solo, first, second, dist[o[first], o[second]], sw.pickup_from_first_origin)
            if _within(g["detour_a"], p.max_detour_m, strict) and _within(g["detour_b"], p.max_detour_m, strict):
                rr[(first, second)] = g["saving"] if authors else 2 * AUTHORS_BONUS + g["saving"]
    for c, vi in enumerate(active):
        veh = engine.vehicles[vi]
        pk = dist[veh.node, o[np.asarray(s)]]
        near = [r for r, k in zip(s, pk, strict=True) if _within(k, p.max_pickup_m, True)]
        if veh.p0 < 0:
            for r in near:
                pk_w = dist[o[r], veh.node] if sw.pickup_from_first_origin else dist[veh.node, o[r]]
                if pk_w <= p.max_pickup_m:
                    cols.append((c, (r,)))
                    values.append(AUTHORS_BONUS - pk_w)
            for a_i in range(len(near)):
                for b_i in range(a_i + 1, len(near)):
                    a, b = near[a_i], near[b_i]
                    key = (a, b) if (a, b) in rr else ((b, a) if (b, a) in rr else None)
                    if key is None:
                        continue
                    value = rr[key]
                    if not authors:
                        value -= float(dist[veh.node, o[key[0]]])
                    cols.append((c, tuple(sorted((a, b), key=lambda x: pos[x]))))
                    values.append(value)
        else:
            a = veh.p0
            for r in near:
                from_vehicle = engine._taker_geometry_one(veh, r, from_vehicle=True)
                if not (
                    _within(from_vehicle["detour_a"], p.max_detour_m, strict)
                    and _within(from_vehicle["detour_b"], p.max_detour_m, strict)
                ):
                    continue
                g = engine._taker_geometry_one(veh, r, from_vehicle=not sw.pickup_from_first_origin)
                if not (
                    _within(g["detour_a"], p.max_detour_m, strict) and _within(g["detour_b"], p.max_detour_m, strict)
                ):
                    continue
                pk_w = dist[o[a], o[r]] if sw.pickup_from_first_origin else g["pk"]
                if pk_w > p.max_pickup_m:
                    continue
                cols.append((c, (r,)))
                values.append(AUTHORS_BONUS + g["saving"] - pk_w)
    col_vehicle = [c for c, _ in cols]
    req1 = [pos[trip[0]] if len(trip) == 1 else min(pos[trip[0]], pos[trip[1]]) for _, trip in cols]
    req2 = [-1 if len(trip) == 1 else max(pos[trip[0]], pos[trip[1]]) for _, trip in cols]
    # Only trips worth more than leaving everyone unmatched can be chosen; dropping the rest changes nothing.
    keep = [i for i, v in enumerate(values) if v > 0]
    model = TripPackingModel(
        len(s),
        len(active),
        [col_vehicle[i] for i in keep],
        [req1[i] for i in keep],
        [req2[i] for i in keep],
        quantize([values[i] for i in keep]),
        name="authors-rtv-round",
    )
    decode = [(active[cols[i][0]], cols[i][1]) for i in keep]
    return model, decode
