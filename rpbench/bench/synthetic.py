"""Seeded synthetic decision models shaped like rpbench's real ones.

Used by the model benchmark (:mod:`rpbench.bench.runner`, ``rpbench bench
--synthetic``) and by property tests.  Geometry is a Haikou-sized city
(20 km x 12 km): 60 % of points come from five Gaussian hot spots, the rest
are uniform, and road distance is 1.3 x the straight line.  Values follow the
paper's utilities, quantised to integral model units (:func:`~rpbench.model.quantize`):

* :func:`assignment` — one batch round (paper Eqs. 1-4 and 14): each
  passenger is feasible with its nearest 5-20 % of vehicles, worth
  ``-pickup`` on a vacant vehicle and ``saving - pickup`` on a partially
  occupied one (Eq. 7), plus a keep-waiting option worth ``-U(1.5, 4) km``.
* :func:`pairing` — the oracle (docs/algorithms.md §4): orders sorted by request
  time, each paired with up to ``partners / 2`` of its next orders in time
  whose pooled trip keeps both detours ``<= 3 km``; value = the saving
  ``l_i + l_j - L`` (Eq. 5).  ``objective="weight"`` keeps positive savings
  only (Oracle-1 drops the others).
* :func:`trip_packing` — RTV-2 (docs/algorithms.md §3.3): one-request trips on the
  nearest vehicles, two-request trips on vehicles near both origins, valued
  ``c_ko·|T| + e - pickup``.

Every generator is a pure function of its arguments (same seed, same model).
"""

from __future__ import annotations

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import OBJECTIVES, AssignmentModel, Model, PairingModel, TripPackingModel, quantize

CITY_M = (20_000.0, 12_000.0)
ROAD_FACTOR = 1.3
MAX_DETOUR_M = 3_000.0
C_KO_M = 3_000.0


def _rng(seed: int, stream: int) -> np.random.Generator:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ParameterError(f"seed {seed!r} must be an integer >= 0")
    return np.random.default_rng(np.random.SeedSequence([int(seed), stream]))


def _check_count(name: str, value, low: int = 0) -> int:
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < low:
        raise ParameterError(f"{name} = {value!r} must be an integer >= {low}")
    return int(value)


def city_points(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` points (metres): 60 % near five hot spots, 40 % uniform over the city."""
    size = np.asarray(CITY_M)
    centres = np.random.default_rng(12345).uniform(0.2, 0.8, (5, 2)) * size  # the same city for every seed
    hot = rng.random(n) < 0.6
    pts = rng.uniform(0.0, 1.0, (n, 2)) * size
    pts[hot] = centres[rng.integers(0, 5, hot.sum())] + rng.normal(0.0, 1_500.0, (hot.sum(), 2))
    return np.clip(pts, 0.0, size)


def road_m(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Road distance between point arrays (straight line x ``ROAD_FACTOR``)."""
    return ROAD_FACTOR * np.hypot(*(np.asarray(a) - np.asarray(b)).T)


# ------------------------------------------------------------------ assignment
def assignment(
    n_passengers: int,
    n_vehicles: int,
    *,
    seed: int = 0,
    density: tuple[float, float] = (0.05, 0.20),
    occupied_share: float = 0.3,
    wait: bool = True,
    unit_m: float = 1e-3,
    name: str | None = None,
) -> AssignmentModel:
    """A batch-round model: each passenger sees its nearest ``U(density)`` share of vehicles."""
    from scipy.spatial import cKDTree

    P = _check_count("n_passengers", n_passengers)
    V = _check_count("n_vehicles", n_vehicles)
    lo, hi = density
    if not 0 < lo <= hi <= 1:
        raise ParameterError(f"density {density!r} must satisfy 0 < low <= high <= 1")
    rng = _rng(seed, 1)
    pax, veh = city_points(rng, P), city_points(rng, V)
    k = np.clip(np.rint(rng.uniform(lo, hi, P) * V), 1, V).astype(np.int64) if V else np.zeros(P, np.int64)
    if V and P:
        kmax = int(k.max())
        _, nearest = cKDTree(veh).query(pax, k=kmax)
        nearest = nearest.reshape(P, kmax)
        keep = np.arange(kmax)[None, :] < k[:, None]
        col_p = np.repeat(np.arange(P), k)
        col_v = nearest[keep]
    else:
        col_p = col_v = np.zeros(0, np.int64)
    pickup = road_m(pax[col_p], veh[col_v])
    occupied = rng.random(V) < occupied_share
    saving = np.where(occupied, rng.uniform(0.0, 4_000.0, V), 0.0)  # Eq. 7: e - l^pk on a V1 vehicle
    values = quantize(saving[col_v] - pickup, unit_m)
    if wait:
        col_p = np.concatenate([col_p, np.arange(P)])
        col_v = np.concatenate([col_v, np.full(P, -1)])
        values = np.concatenate([values, quantize(-rng.uniform(1_500.0, 4_000.0, P), unit_m)])
    return AssignmentModel(P, V, col_p, col_v, values, unit_m=unit_m, name=name or f"assignment-{P}x{V}-s{seed}")


# --------------------------------------------------------------------- pairing
def _pool_saving(oa, da, ob, db):
    """Saving ``l_a + l_b - L`` and larger detour of ``o_a -> o_b -> drops`` (Eq. 5).

    The drop order is the shorter one whose detours are both ``<= 3 km``
    (the oracle's ``min_feasible`` rule); the detour returned is ``inf`` when
    neither order is feasible.
    """
    la, lb = road_m(oa, da), road_m(ob, db)
    head, ob_da, ob_db, da_db = road_m(oa, ob), road_m(ob, da), road_m(ob, db), road_m(da, db)
    total_a = head + ob_da + da_db  # drop a first
    det_a = np.maximum(head + ob_da - la, ob_da + da_db - lb)
    total_b = head + ob_db + da_db  # drop b first
    det_b = np.maximum(head + ob_db + da_db - la, ob_db - lb)
    ok_a, ok_b = det_a <= MAX_DETOUR_M, det_b <= MAX_DETOUR_M
    use_a = ok_a & (~ok_b | (total_a <= total_b))
    total = np.where(use_a, total_a, total_b)
    detour = np.where(use_a, det_a, np.where(ok_b, det_b, np.inf))
    return la + lb - total, detour


def pairing(
    n_orders: int,
    *,
    partners: int = 30,
    seed: int = 0,
    objective: str = "weight",
    unit_m: float = 1.0,
    name: str | None = None,
) -> PairingModel:
    """An oracle-shaped pairing model with about ``partners`` candidate partners per order.

    Values default to whole metres (``unit_m=1``): savings of long shared
    trips exceed 8.4 km, beyond PyMatching's exact integer range in
    millimetres (see :mod:`rpbench.backends.matching`).
    """
    n = _check_count("n_orders", n_orders)
    half = max(1, _check_count("partners", partners, 1) // 2)
    if objective not in OBJECTIVES:
        raise ParameterError(f"objective {objective!r} unknown; expected one of {', '.join(OBJECTIVES)}")
    rng = _rng(seed, 2)
    o, d = city_points(rng, n), city_points(rng, n)
    window = 32 * half  # later orders considered per order (a few % are kept)
    parts = []
    for start in range(0, n, 4096):  # blocks bound memory to a few tens of MB
        i = np.repeat(np.arange(start, min(start + 4096, n)), window)
        j = i + np.tile(np.arange(1, window + 1), len(i) // window)
        ok = j < n
        i, j = i[ok], j[ok]
        saving, detour = _pool_saving(o[i], d[i], o[j], d[j])
        keep = detour <= MAX_DETOUR_M
        if objective == "weight":
            keep &= quantize(saving, unit_m) > 0
        i, j, saving = i[keep], j[keep], saving[keep]
        # each order keeps its `half` best later partners: about `partners` candidates per order in all
        order = np.lexsort((j, -saving, i))
        i, j, saving = i[order], j[order], saving[order]
        keep = (np.arange(len(i)) - np.searchsorted(i, i)) < half
        parts.append((i[keep], j[keep], saving[keep]))
    col_a, col_b, saving_m = (np.concatenate(p) for p in zip(*parts, strict=True)) if parts else (np.zeros(0),) * 3
    return PairingModel(
        n,
        col_a,
        col_b,
        quantize(saving_m, unit_m),
        objective=objective,
        unit_m=unit_m,
        name=name or f"pairing-{n}-{objective}-s{seed}",
    )


# ---------------------------------------------------------------- trip packing
def trip_packing(
    n_requests: int,
    n_vehicles: int,
    *,
    seed: int = 0,
    vehicles_per_request: int = 10,
    partners: int = 6,
    occupied_share: float = 0.3,
    unit_m: float = 1e-3,
    name: str | None = None,
) -> TripPackingModel:
    """An RTV-2 trip-packing model (one- and two-request trips on nearby vehicles)."""
    from scipy.spatial import cKDTree

    R = _check_count("n_requests", n_requests)
    V = _check_count("n_vehicles", n_vehicles)
    k = min(_check_count("vehicles_per_request", vehicles_per_request, 1), V)
    rng = _rng(seed, 3)
    o, d, veh = city_points(rng, R), city_points(rng, R), city_points(rng, V)
    occupied = rng.random(V) < occupied_share
    if R == 0 or V == 0:
        z = np.zeros(0, np.int64)
        return TripPackingModel(R, V, z, z, z, np.zeros(0), unit_m=unit_m, name=name or f"trip-packing-{R}x{V}-s{seed}")
    _, near = cKDTree(veh).query(o, k=k)
    near = near.reshape(R, k)
    # one-request trips: c_ko - pickup on a vacant vehicle, c_ko + saving - pickup on an occupied one
    r1 = np.repeat(np.arange(R), k)
    v1 = near.ravel()
    bonus = np.where(occupied[v1], rng.uniform(0.0, 3_000.0, len(v1)), 0.0)
    val1 = C_KO_M + bonus - road_m(veh[v1], o[r1])
    # two-request trips: request pairs close in time (index) that pool well, on vacant vehicles near both
    w = max(1, 2 * _check_count("partners", partners, 0))
    a = np.repeat(np.arange(R), w)
    b = a + np.tile(np.arange(1, w + 1), R)
    ok = b < R
    a, b = a[ok], b[ok]
    saving, detour = _pool_saving(o[a], d[a], o[b], d[b])
    good = (detour <= MAX_DETOUR_M) & (saving > 0)
    a, b, saving = a[good], b[good], saving[good]
    common = near[a][:, :, None] == near[b][:, None, :]  # (pairs, k, k): vehicle near both
    pair_idx, slot, _ = np.nonzero(common)
    v2 = near[a[pair_idx], slot]
    vacant = ~occupied[v2]
    pair_idx, v2 = pair_idx[vacant], v2[vacant]
    a2, b2 = a[pair_idx], b[pair_idx]
    val2 = 2 * C_KO_M + saving[pair_idx] - road_m(veh[v2], o[a2])
    col_v = np.concatenate([v1, v2])
    col_r1 = np.concatenate([r1, a2])
    col_r2 = np.concatenate([np.full(len(r1), -1), b2])
    values = quantize(np.concatenate([val1, val2]), unit_m)
    return TripPackingModel(
        R, V, col_v, col_r1, col_r2, values, unit_m=unit_m, name=name or f"trip-packing-{R}x{V}-s{seed}"
    )


# ---------------------------------------------------------------- benchmark sets
#: Named model sets for ``rpbench bench --synthetic --sizes NAME`` (structure, size arguments).
SUITES: dict[str, list[tuple[str, tuple[int, ...]]]] = {
    "tiny": [("assignment", (5, 12)), ("pairing", (30,)), ("trip_packing", (8, 5))],
    "small": [
        ("assignment", (20, 100)),
        ("assignment", (100, 500)),
        ("pairing", (2_000,)),
        ("trip_packing", (200, 100)),
    ],
    "default": [
        ("assignment", (20, 100)),
        ("assignment", (100, 500)),
        ("assignment", (500, 2_000)),
        ("assignment", (2_000, 5_000)),
        ("pairing", (2_000,)),
        ("pairing", (50_000,)),
        ("trip_packing", (200, 100)),
        ("trip_packing", (1_000, 500)),
    ],
}


def suite(name: str = "default", *, seed: int = 0, objectives: tuple[str, ...] = ("weight",)) -> list[Model]:
    """The models of a named benchmark set (pairing once per objective)."""
    if name not in SUITES:
        raise ParameterError(f"synthetic size set {name!r} unknown; expected one of {', '.join(SUITES)}")
    models: list[Model] = []
    for structure, args in SUITES[name]:
        if structure == "assignment":
            models.append(assignment(*args, seed=seed))
        elif structure == "trip_packing":
            models.append(trip_packing(*args, seed=seed))
        else:
            models.extend(pairing(*args, seed=seed, objective=obj) for obj in objectives)
    return models
