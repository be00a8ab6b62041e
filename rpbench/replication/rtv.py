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

from typing import Any, Protocol

import numpy as np

from rpbench.model import TripPackingModel, quantize
from rpbench.network import Distances
from rpbench.replication.geometry import TakerGeometry
from rpbench.replication.switches import Switches
from rpbench.replication.weights import AUTHORS_BONUS, StrategyRules
from rpbench.scenarios.base import Scenario


class EngineView(Protocol):
    """What a batch's trip packing reads of the engine (:class:`rpbench.replication.engine.AuthorsEngine`,
    which calls it: a protocol here, so that the two modules do not import each other)."""

    switches: Switches
    scenario: Scenario
    distances: Distances
    origin: np.ndarray
    destination: np.ndarray
    solo_m: np.ndarray
    vehicles: list[Any]
    rules: StrategyRules

    def one_taker_geometry(self, veh: Any, b: int, *, from_vehicle: bool) -> TakerGeometry[float]: ...


#: Per column of a round's model: the vehicle's index in the fleet and the trip's passengers.
Trip = tuple[int, tuple[int, ...]]


def pair_legs(
    dist: np.ndarray,
    origin: np.ndarray,
    destination: np.ndarray,
    solo_m: np.ndarray,
    first: int,
    second: int,
    strict_ties: bool,
) -> tuple[bool, float, float, float]:
    """Drop-off order of ``second`` joining ``first`` from O_second.

    Returns (fofo, leg1, leg2, shared) with the authors' rule: first-on-first-off iff its two legs sum
    strictly less (``strict_ties``; else ties go to first-on-first-off).
    """
    f1, f2 = dist[origin[second], destination[first]], dist[destination[first], destination[second]]
    l1, l2 = solo_m[second], dist[destination[second], destination[first]]
    fofo = (f1 + f2 < l1 + l2) if strict_ties else (f1 + f2 <= l1 + l2)
    return (True, f1, f2, f1) if fofo else (False, l1, l2, l1)


def authors_pair_geometry(
    dist: np.ndarray,
    origin: np.ndarray,
    destination: np.ndarray,
    solo_m: np.ndarray,
    first: int,
    second: int,
    lead_m: float,
    strict_ties: bool,
) -> TakerGeometry[float]:
    """Rides, shared distance, saving and detours of ``first`` (in the vehicle ``lead_m`` before O_second)
    and ``second``; the pick-up weight is ``lead_m``."""
    fofo, leg1, leg2, shared = pair_legs(dist, origin, destination, solo_m, first, second, strict_ties)
    first_ride = lead_m + leg1 if fofo else lead_m + leg1 + leg2
    second_ride = leg1 + leg2 if fofo else leg1
    saving = solo_m[first] + solo_m[second] - (first_ride + second_ride - shared)
    return TakerGeometry(
        pickup_m=lead_m,
        lead_m=lead_m,
        fofo=fofo,
        first_ride_m=first_ride,
        second_ride_m=second_ride,
        shared_m=shared,
        saving_m=saving,
        first_detour_m=first_ride - solo_m[first],
        second_detour_m=second_ride - solo_m[second],
        rest_m=leg1 + leg2,
    )


def _within(x: float, limit: float, strict: bool) -> bool:
    return x < limit if strict else x <= limit


def build_round(
    engine: EngineView, t: float, seekers: list[int], active: list[int]
) -> tuple[TripPackingModel, list[Trip]]:
    """The round's trip-packing model and, per column, (vehicle index, request tuple)."""
    switches, params = engine.switches, engine.scenario.params
    dist, origin, destination, solo = engine.distances.dist, engine.origin, engine.destination, engine.solo_m
    from_first_origin = switches.pickup_from_first_origin
    strict = authors = switches.authors_weights
    s = list(seekers)
    pos = {r: i for i, r in enumerate(s)}
    cols: list[tuple[int, tuple[int, ...]]] = []
    values: list[float] = []

    def within_detours(g: TakerGeometry[float]) -> bool:
        return _within(g.first_detour_m, params.max_detour_m, strict) and _within(
            g.second_detour_m, params.max_detour_m, strict
        )

    # Request-request edges: first = the later-listed passenger (the authors' loop order), pick-up from its origin.
    rr: dict[tuple[int, int], float] = {}
    for i in range(len(s)):
        for j in range(i + 1, len(s)):
            first, second = s[j], s[i]
            lead = dist[origin[first], origin[second]]
            g = authors_pair_geometry(dist, origin, destination, solo, first, second, lead, from_first_origin)
            if within_detours(g):
                rr[(first, second)] = g.saving_m if authors else 2 * AUTHORS_BONUS + g.saving_m
    for c, vi in enumerate(active):
        veh = engine.vehicles[vi]
        pk = dist[veh.node, origin[np.asarray(s)]]
        near = [r for r, k in zip(s, pk, strict=True) if _within(k, params.max_pickup_m, True)]
        if veh.passenger < 0:
            reversed_pickup = from_first_origin and engine.rules.reversed_vacant_pickup
            for r in near:
                pk_w = dist[origin[r], veh.node] if reversed_pickup else dist[veh.node, origin[r]]
                if pk_w <= params.max_pickup_m:
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
                        value -= float(dist[veh.node, origin[key[0]]])
                    cols.append((c, tuple(sorted((a, b), key=lambda x: pos[x]))))
                    values.append(value)
        else:
            a = veh.passenger
            for r in near:
                if not within_detours(engine.one_taker_geometry(veh, r, from_vehicle=True)):
                    continue
                g = engine.one_taker_geometry(veh, r, from_vehicle=not from_first_origin)
                if not within_detours(g):
                    continue
                pk_w = dist[origin[a], origin[r]] if from_first_origin else g.pickup_m
                if pk_w > params.max_pickup_m:
                    continue
                cols.append((c, (r,)))
                values.append(AUTHORS_BONUS + g.saving_m - pk_w)
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
