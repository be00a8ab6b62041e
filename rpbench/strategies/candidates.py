"""Feasible passenger-vehicle options of a round, and the assignment model built from them.

Shared by every strategy of the paper's batch-matching family (NP, MB,
FL-no_delay, FL) and by those built on it (VF, MSA, FL-perfect, Hindsight; a dispatcher outside
Python through :mod:`.edges`): they differ only in the utility they put on the same
feasible options (paper §2, Eqs. 1-4; pairing conditions of §2.1):

* vacant option (p, v ∈ V0): pick-up ``pk = pre_v + l(node_v, o_p) <= R̄``;
* join option (p, v ∈ V1 carrying A): ``POOL(A, p, h, δ, pre)`` feasible
  (docs/algorithms.md §1.1: pick-up <= R̄, both detours <= D̄).

:class:`NearTable` pre-filters the vacant options: which node pairs lie within R̄.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from rpbench.geometry import ORDER_RULES, TOLERANCE_M, choose_order, pair_geometry
from rpbench.model import AssignmentModel, quantize
from rpbench.model.kernels import read_only
from rpbench.scenarios.base import Params
from rpbench.strategies.base import Kind, RoundModel, RoundState

#: Utility of keeping a passenger waiting when the strategy has no waiting
#: option (MB, FL-no_delay, NP): -M with M = 10^6 m, so a passenger is
#: assigned whenever any vehicle is feasible (docs/algorithms.md A13).
NO_WAIT_UTILITY_M = -1e6
VALUE_UNIT_M = 1e-3  # utilities enter the model in millimetres


@dataclass(frozen=True)
class VacantOptions:
    p: np.ndarray  # passenger position in the state
    v: np.ndarray  # position in the state's V0 arrays
    pickup_m: np.ndarray


@dataclass(frozen=True)
class JoinOptions:
    p: np.ndarray
    v: np.ndarray  # position in the state's V1 arrays
    pickup_m: np.ndarray
    saving_m: np.ndarray  # e(v_p', p), Eq. (5)
    fofo: np.ndarray
    #: The pooled route still to drive from the vehicle's position to the last drop-off (pre + L - δ).
    remaining_m: np.ndarray

    @classmethod
    def empty(cls) -> JoinOptions:
        none = np.zeros(0, np.int64)
        return cls(none, none, np.zeros(0), np.zeros(0), np.zeros(0, bool), np.zeros(0))

    def take(self, keep: np.ndarray) -> JoinOptions:
        """The options ``keep`` selects (a boolean mask or indices)."""
        return JoinOptions(
            self.p[keep],
            self.v[keep],
            self.pickup_m[keep],
            self.saving_m[keep],
            self.fofo[keep],
            self.remaining_m[keep],
        )


def vacant_options(state: RoundState) -> VacantOptions:
    """Every (waiting passenger, vacant vehicle) pair within R̄."""
    if state.n_passengers == 0 or state.n_v0 == 0:
        empty = np.zeros(0, np.int64)
        return VacantOptions(empty, empty, np.zeros(0))
    limit = state.params.max_pickup_m + TOLERANCE_M
    p, v, pk = _within_pickup(state, state.v0_node, state.v0_pre_m, limit)
    return VacantOptions(p, v, pk)


def join_options(state: RoundState, order_rule: str = "min_feasible") -> JoinOptions:
    """Every (waiting passenger, partially occupied vehicle) pair that POOL accepts."""
    if state.n_passengers == 0 or state.n_v1 == 0:
        return JoinOptions.empty()
    limit = state.params.max_pickup_m + TOLERANCE_M
    pre = np.asarray(state.v1_pre_m, dtype=np.float64)
    if order_rule not in ORDER_RULES or not np.all(pre >= 0):
        return _join_options_numpy(state, order_rule)
    p, v, pk, saving, fofo, remaining = _join_pairs(
        near_table(state.dist, limit).reach,
        state.dist,
        np.asarray(state.p_origin, dtype=np.int64),
        np.asarray(state.p_destination, dtype=np.int64),
        np.asarray(state.p_solo_m, dtype=np.float64),
        np.asarray(state.v1_node, dtype=np.int64),
        pre,
        np.asarray(state.v1_delta_m, dtype=np.float64),
        np.asarray(state.v1_origin, dtype=np.int64),
        np.asarray(state.v1_destination, dtype=np.int64),
        np.asarray(state.v1_solo_m, dtype=np.float64),
        float(state.params.max_pickup_m),
        float(state.params.max_detour_m),
        order_rule == "min_feasible",
    )
    return JoinOptions(p, v, pk, saving, fofo, remaining)


def _join_options_numpy(state: RoundState, order_rule: str) -> JoinOptions:
    """:func:`join_options` by numpy passes and :func:`~rpbench.geometry.pair_geometry` (the compiled pass's
    reference; taken for negative distances before the vehicles' next nodes and for an unknown rule)."""
    # Cheap pick-up filter first: most pairs fail R̄.
    limit = state.params.max_pickup_m + TOLERANCE_M
    p, v, _ = _within_pickup(state, state.v1_node, state.v1_pre_m, limit)
    g = pair_geometry(
        state.dist,
        state.v1_origin[v],
        state.v1_destination[v],
        state.v1_solo_m[v],
        state.p_origin[p],
        state.p_destination[p],
        state.p_solo_m[p],
        state.v1_node[v],
        state.v1_delta_m[v],
        state.v1_pre_m[v],
        state.params.max_detour_m,
    )
    r = choose_order(g, state.params.max_pickup_m, order_rule)
    ok = r.feasible
    remaining = state.v1_pre_m[v] + r.length - state.v1_delta_m[v]
    return JoinOptions(p[ok], v[ok], r.pk[ok], r.saving[ok], r.fofo[ok], remaining[ok])


@njit(cache=True, nogil=True)
def _join_pairs(
    reach, dist, o_b, d_b, l_b, h, pre, delta, o_a, d_a, l_a, max_pickup, max_detour, min_feasible
):  # pragma: no cover - compiled
    """The join options as :func:`_join_options_numpy` finds them, pair by pair in passenger-major order:
    the pick-up screen of :func:`_pickup_pairs`, then POOL's two service orders with the same arithmetic as
    :func:`~rpbench.geometry.pair_geometry` and :func:`~rpbench.geometry.choose_order`."""
    n_p, n_v = len(o_b), len(h)
    pick_lim = max_pickup + TOLERANCE_M
    lim = max_detour + TOLERANCE_M
    # room for every pair, filled in one pass: the screen reads the table once, not once to count
    out_p, out_v = np.empty(n_p * n_v, np.int64), np.empty(n_p * n_v, np.int64)
    out_pk, out_e, out_rem = np.empty(n_p * n_v), np.empty(n_p * n_v), np.empty(n_p * n_v)
    out_fofo = np.empty(n_p * n_v, np.bool_)
    k = 0
    for i in range(n_p):
        for j in range(n_v):
            if not reach[o_b[i], h[j]]:
                continue
            p = dist[h[j], o_b[i]]
            pk = pre[j] + p
            if not pk <= pick_lim:
                continue
            l_ob_da = dist[o_b[i], d_a[j]]
            l_da_db = dist[d_a[j], d_b[i]]
            l_db_da = dist[d_b[i], d_a[j]]
            head = delta[j] + p
            fofo_length = head + l_ob_da + l_da_db
            folo_length = head + l_b[i] + l_db_da
            fofo_ok = (head + l_ob_da - l_a[j] <= lim) and (l_ob_da + l_da_db - l_b[i] <= lim)
            folo_ok = folo_length - l_a[j] <= lim
            if min_feasible:
                fofo = fofo_ok and ((not folo_ok) or fofo_length <= folo_length)
                ok = fofo_ok or folo_ok
            else:
                fofo = fofo_length <= folo_length
                ok = fofo_ok if fofo else folo_ok
            if not (ok and pk <= pick_lim and l_a[j] > TOLERANCE_M and l_b[i] > TOLERANCE_M):
                continue
            length = fofo_length if fofo else folo_length
            out_p[k], out_v[k], out_pk[k], out_fofo[k] = i, j, pk, fofo
            out_e[k] = l_a[j] + l_b[i] - length
            out_rem[k] = pre[j] + length - delta[j]
            k += 1
    # copies of the filled part: the room for every pair is let go at once
    return (
        out_p[:k].copy(),
        out_v[:k].copy(),
        out_pk[:k].copy(),
        out_e[:k].copy(),
        out_fofo[:k].copy(),
        out_rem[:k].copy(),
    )


def _within_pickup(state: RoundState, nodes: np.ndarray, pre_m: np.ndarray, limit_m: float):
    """(passenger, vehicle) position pairs, passenger-major, with pick-up ``pre + l(node, o_p) <= limit``, and
    that pick-up.

    With ``pre >= 0`` only pairs whose road distance alone is within the limit can (:class:`NearTable`), so
    only those are measured; otherwise every pair is.
    """
    pre = np.asarray(pre_m, dtype=np.float64)
    screened = bool(np.all(pre >= 0))
    reach = near_table(state.dist, limit_m).reach if screened else np.ones((1, 1), dtype=bool)
    return _pickup_pairs(
        reach,
        screened,
        state.dist,
        np.asarray(state.p_origin, dtype=np.int64),
        np.asarray(nodes, dtype=np.int64),
        pre,
        float(limit_m),
    )


@njit(cache=True, nogil=True)
def _pickup_pairs(reach, screened, dist, origins, nodes, pre, limit):  # pragma: no cover - compiled
    """Pairs (p, v) in passenger-major order with ``pre[v] + dist[nodes[v], origins[p]] <= limit``, measured only
    where ``reach[origins[p], nodes[v]]`` (when ``screened``), and their pick-up distances."""
    n_p, n_v = len(origins), len(nodes)
    # room for every pair, filled in one pass: the screen reads the table once, not once to count
    p, v, pk = np.empty(n_p * n_v, np.int64), np.empty(n_p * n_v, np.int64), np.empty(n_p * n_v)
    k = 0
    for i in range(n_p):
        for j in range(n_v):
            if not screened or reach[origins[i], nodes[j]]:
                d = pre[j] + dist[nodes[j], origins[i]]
                if d <= limit:
                    p[k], v[k], pk[k] = i, j, d
                    k += 1
    return p[:k].copy(), v[:k].copy(), pk[:k].copy()  # the filled part: the room for every pair is let go


def assignment_round(
    state: RoundState,
    vac: VacantOptions,
    vac_utility_m: np.ndarray,
    join: JoinOptions,
    join_utility_m: np.ndarray,
    wait_utility_m: np.ndarray,
    *,
    name: str,
) -> RoundModel:
    """Assemble the round's AssignmentModel (Eq. 1-4 / 16) and its column decoding.

    Columns are ordered by passenger, then vacant vehicles, then partially
    occupied vehicles (each by vehicle id), then the keep-waiting option:
    a deterministic order the tie canonicalisation relies on.  Model
    vehicle rows are V0 (state order) followed by V1.
    """
    columns = _ordered_columns(state, vac, vac_utility_m, join, join_utility_m, wait_utility_m)
    if columns is None:
        columns = _ordered_columns_numpy(state, vac, vac_utility_m, join, join_utility_m, wait_utility_m)
    passenger, model_vehicle, sim_vehicle, kind, utility, pickup, fofo = columns
    model = AssignmentModel(
        state.n_passengers,
        state.n_v0 + state.n_v1,
        passenger,
        model_vehicle,
        quantize(utility, VALUE_UNIT_M),
        unit_m=VALUE_UNIT_M,
        name=name,
    )
    return RoundModel(
        model=model,
        kind=kind,
        vehicle=sim_vehicle,
        first=state.p_order[passenger],
        second=np.full(len(kind), -1, dtype=np.int64),
        fofo=fofo,
        utility_m=utility,
        pickup_m=pickup,
    )


def _ordered_columns_numpy(state, vac, vac_utility_m, join, join_utility_m, wait_utility_m) -> tuple[np.ndarray, ...]:
    """The columns (passenger, model vehicle row, vehicle id, kind, utility, pick-up, FOFO) in their order."""
    n_p = state.n_passengers
    wait_p = np.arange(n_p)
    passenger = np.concatenate([vac.p, join.p, wait_p])
    model_vehicle = np.concatenate([vac.v, state.n_v0 + join.v, np.full(n_p, -1)])
    sim_vehicle = np.concatenate([state.v0_vehicle[vac.v], state.v1_vehicle[join.v], np.full(n_p, -1)])
    kind = np.concatenate(
        [np.full(len(vac.p), Kind.VACANT), np.full(len(join.p), Kind.JOIN), np.full(n_p, Kind.WAIT)]
    ).astype(np.int8)
    utility = np.concatenate([vac_utility_m, join_utility_m, wait_utility_m]).astype(np.float64)
    pickup = np.concatenate([vac.pickup_m, join.pickup_m, np.full(n_p, np.nan)])
    fofo = np.concatenate([np.zeros(len(vac.p), bool), join.fofo, np.zeros(n_p, bool)])
    # Deterministic column order: passenger, kind (as numbers: wait < vacant < join), vehicle id.
    order = np.lexsort((sim_vehicle, kind, passenger))
    return (
        passenger[order],
        model_vehicle[order],
        sim_vehicle[order],
        kind[order],
        utility[order],
        pickup[order],
        fofo[order],
    )


def _ordered_columns(state, vac, vac_utility_m, join, join_utility_m, wait_utility_m) -> tuple[np.ndarray, ...] | None:
    """:func:`_ordered_columns_numpy` in one compiled pass, for options and utilities of the usual shapes
    and ranges (None otherwise: the numpy passes then build, or refuse, the same columns)."""
    arrays = []
    for raw, dtype in (
        (vac.p, np.int64), (vac.v, np.int64), (vac_utility_m, np.float64), (vac.pickup_m, np.float64),
        (join.p, np.int64), (join.v, np.int64), (join_utility_m, np.float64), (join.pickup_m, np.float64),
        (join.fofo, np.bool_), (wait_utility_m, np.float64),
    ):  # fmt: skip
        if type(raw) is np.ndarray and raw.dtype == dtype and raw.ndim == 1:  # the usual case: as it is
            arrays.append(raw)
            continue
        arr = np.asarray(raw)
        if arr.ndim != 1 or (len(arr) and arr.dtype.kind not in ("b" if dtype is np.bool_ else "biuf")):
            return None
        if dtype is not np.float64 and arr.dtype.kind == "f":
            return None  # float indices: the numpy passes say what they make of them
        arrays.append(arr.astype(dtype, copy=False))
    vp, vv, vu, vk, jp, jv, ju, jk, jf, wu = arrays
    v0, v1 = np.asarray(state.v0_vehicle, np.int64), np.asarray(state.v1_vehicle, np.int64)
    fits, *columns = _columns_kernel(vp, vv, vu, vk, jp, jv, ju, jk, jf, wu, v0, v1, state.n_passengers)
    return tuple(columns) if fits else None


@njit(cache=True, nogil=True)
def _columns_kernel(
    vac_p, vac_v, vac_u, vac_pk, join_p, join_v, join_u, join_pk, join_fofo, wait_u, v0_vehicle, v1_vehicle, n_p
):  # pragma: no cover - compiled
    """Whether the inputs fit, then the ordered columns of :func:`_ordered_columns_numpy`, sorted by one stable
    sort of a mixed-radix key (passenger, kind, vehicle id)."""
    n_vac, n_join = len(vac_p), len(join_p)
    n = n_vac + n_join + n_p
    n_v0, n_v1 = len(v0_vehicle), len(v1_vehicle)
    passenger = np.zeros(n, np.int64)
    row = np.zeros(n, np.int64)
    vehicle = np.zeros(n, np.int64)
    kind = np.zeros(n, np.int8)
    utility = np.zeros(n)
    pickup = np.zeros(n)
    fofo = np.zeros(n, np.bool_)
    fits = len(vac_v) == n_vac and len(vac_u) == n_vac and len(vac_pk) == n_vac and len(wait_u) == n_p
    fits = fits and len(join_v) == n_join and len(join_u) == n_join and len(join_pk) == n_join
    fits = fits and len(join_fofo) == n_join
    for i in range(n_vac if fits else 0):
        fits = fits and 0 <= vac_v[i] < n_v0
        if fits:
            passenger[i], row[i], vehicle[i], kind[i] = vac_p[i], vac_v[i], v0_vehicle[vac_v[i]], 1
    for i in range(n_join if fits else 0):
        fits = fits and 0 <= join_v[i] < n_v1
        if fits:
            j = n_vac + i
            passenger[j], row[j], vehicle[j], kind[j] = join_p[i], n_v0 + join_v[i], v1_vehicle[join_v[i]], 2
    for p in range(n_p if fits else 0):
        j = n_vac + n_join + p
        passenger[j], row[j], vehicle[j], kind[j] = p, -1, -1, 0
    top = 0
    for j in range(n if fits else 0):
        fits = fits and 0 <= passenger[j] < n_p and vehicle[j] >= -1
        top = max(top, vehicle[j])
    if not fits or float(n_p) * 3.0 * (top + 2) >= 2.0**62:
        return False, passenger, row, vehicle, kind, utility, pickup, fofo
    key = (passenger * 3 + kind) * (top + 2) + (vehicle + 1)
    order = np.argsort(key, kind="mergesort")
    for j in range(n):
        c = order[j]
        if c < n_vac:
            utility[j], pickup[j] = vac_u[c], vac_pk[c]
        elif c < n_vac + n_join:
            utility[j], pickup[j], fofo[j] = join_u[c - n_vac], join_pk[c - n_vac], join_fofo[c - n_vac]
        else:
            utility[j], pickup[j] = wait_u[c - n_vac - n_join], np.nan
    return True, passenger[order], row[order], vehicle[order], kind[order], utility, pickup, fofo


def load_candidate_kernels() -> None:
    """Load (or compile) the kernels now: the first call of each costs a one-off load of its machine code."""
    i, f = np.zeros(0, np.int64), np.zeros(0)
    _columns_kernel(i, i, f, f, i, i, f, f, np.zeros(0, np.bool_), f, i, i, 0)
    reach = np.ones((1, 1), dtype=bool)
    for dist in (np.zeros((1, 1)), read_only(np.zeros((1, 1)))):  # a run's distance table is read-only
        _pickup_pairs(reach, True, dist, i, i, f, 0.0)
        _join_pairs(reach, dist, i, i, f, i, f, f, i, i, f, 0.0, 0.0, True)


# Which node pairs lie within a distance: a table that pre-filters pick-up candidates.
#
# A round's candidate search asks, for every (vehicle, passenger) pair, whether
# ``pre + l(node, origin) <= R̄``.  Gathering ``l`` for all pairs from the
# all-pairs table (120 MB for Haikou, one row per vehicle node) costs about one
# cache miss per pair, while only a few per cent of node pairs are within R̄.
# Since ``pre >= 0``, a pair can only qualify if ``l(node, origin) <= R̄``
# alone.  A boolean table stored by *destination* answers that for a round from
# one short row per passenger origin (3.9 kB for Haikou), which stays in cache;
# the exact test then runs on the few pairs that pass.
@dataclass(frozen=True, eq=False)
class NearTable:
    """``reach[v, u]`` is True when ``dist[u, v] <= threshold_m`` (row: the destination node)."""

    dist: np.ndarray
    threshold_m: float
    reach: np.ndarray  # bool (n, n)

    #: Source rows compared per block while transposing (bounds the temporary to block x n booleans).
    BLOCK = 256

    @classmethod
    def build(cls, dist: np.ndarray, threshold_m: float) -> NearTable:
        n = dist.shape[0]
        reach = np.empty((dist.shape[1], n), dtype=bool)
        for start in range(0, n, cls.BLOCK):  # blockwise: a whole-table bool transpose is 4x slower
            reach[:, start : start + cls.BLOCK] = (dist[start : start + cls.BLOCK] <= threshold_m).T
        return cls(dist, float(threshold_m), reach)

    def mask(self, from_nodes: np.ndarray, to_nodes: np.ndarray) -> np.ndarray:
        """Boolean ``(len(to_nodes), len(from_nodes))``: ``dist[from, to] <= threshold`` (rows: ``to_nodes``)."""
        return self.reach[np.asarray(to_nodes, dtype=np.int64)][:, np.asarray(from_nodes, dtype=np.int64)]


_last: NearTable | None = None


def prepare_tables(dist: np.ndarray, params: Params) -> None:
    """Build now the table :func:`vacant_options` and :func:`join_options` read for pick-ups within R̄ (kept
    afterwards): a one-off cost of the run (tens of milliseconds for Haikou), not of its first round."""
    near_table(dist, params.max_pickup_m + TOLERANCE_M)


def near_table(dist: np.ndarray, threshold_m: float) -> NearTable:
    """The :class:`NearTable` of ``dist`` (the same array object) at ``threshold_m``, built once and kept.

    One table is kept: a simulation asks for the same one every round, and a
    new distance table or threshold replaces it.
    """
    global _last
    if _last is None or _last.dist is not dist or _last.threshold_m != float(threshold_m):
        _last = NearTable.build(dist, threshold_m)
    return _last
