"""The compiled sweeps against a numpy formulation (segmented log sums, exp, bincount), and the pair values
they derive against a cell-by-cell reference."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.predict._arrays import segment_exclusive_cumsum, segment_sums
from rpbench.predict.config import PredictConfig
from rpbench.predict.fixed_point import PairSums, System, sweep
from rpbench.predict.match_sets import ListGeometry, Matching

from .conftest import make_instance


def random_geometry(
    rng, n_od: int, n_classes: int, n_nodes: int = 9, unreachable: float = 0.0, **rules
) -> ListGeometry:
    """Seekers and classes on a random distance matrix of coarse values (ties, thresholds met exactly), a
    share ``unreachable`` of them infinite."""
    dist = rng.integers(0, 8, (n_nodes, n_nodes)).astype(np.float64) * 250.0
    dist[rng.random(dist.shape) < unreachable] = np.inf
    np.fill_diagonal(dist, 0.0)
    return ListGeometry(
        origin=rng.integers(0, n_nodes, n_od),
        destination=rng.integers(0, n_nodes, n_od),
        solo_m=rng.integers(1, 9, n_od) * 250.0,
        class_head=rng.integers(0, n_nodes, n_classes),
        class_rest_m=rng.integers(0, 8, n_classes) * 250.0,
        class_dest=rng.integers(0, n_nodes, n_classes),
        d_lim=rules.get("d_lim", 1000.0),
        keep_nonpositive=rules.get("keep_nonpositive", False),
        min_feasible=rules.get("min_feasible", True),
        distances=lambda: dist,
    )


def random_lists(seed: int, n_od: int = 40, n_classes: int = 30, empty_share: float = 0.2, block_classes: int = 20):
    """Seeker lists of random lengths (some empty) over random classes of a random geometry."""
    rng = np.random.default_rng(seed)
    lens = rng.integers(1, 12, n_od) * (rng.random(n_od) > empty_share)
    off = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
    cls = np.concatenate([rng.choice(n_classes, k, replace=False) for k in lens]).astype(np.int32)
    geometry = random_geometry(rng, n_od, n_classes)
    matching = Matching.from_lists(off, cls, geometry, n_classes=n_classes, limit=block_classes)
    lam = rng.uniform(0, 0.01, n_od) * (rng.random(n_od) > 0.1)  # some λ = 0
    log_q = np.log1p(-rng.uniform(0, 0.9, n_classes))
    return matching, lam, log_q


def reference_sweep(matching: Matching, lam: np.ndarray, log_q: np.ndarray):
    """H_c, log(1 - p_s) and the pair sums, written the numpy way (one exp per pair)."""
    off, cls = matching.seeker_off, matching.cls
    owner = np.repeat(np.arange(len(lam)), np.diff(off))
    v = log_q[cls]
    with np.errstate(divide="ignore"):
        weight = lam[owner] * np.exp(segment_exclusive_cumsum(v, off))  # λ_s Π_{c' ≻ c} Q_c'
    pair = weight * -np.expm1(v)
    values = [np.ones(len(cls)), matching.saving_m, matching.shared_m, matching.seeker_detour_m]
    by_class = np.stack([np.bincount(cls, weights=weight * x, minlength=len(log_q)) for x in values], axis=1)
    by_seeker = np.stack([segment_sums(pair * x, off) for x in values], axis=1)
    return by_class[:, 0], segment_sums(v, off), by_class, by_seeker


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("chunk_pairs", [1, 5, 64, 1 << 24])
@pytest.mark.parametrize("block_classes", [1, 20, 1 << 16])
def test_sweep_equals_the_log_space_reference(seed, chunk_pairs, block_classes):
    matching, lam, log_q = random_lists(seed, block_classes=block_classes)
    system = System.build(None, matching, lam, PredictConfig())
    h_ref, lnp_ref, cls_ref, seek_ref = reference_sweep(matching, lam, log_q)
    h, lnp = sweep(system, log_q, chunk_pairs=chunk_pairs)
    np.testing.assert_allclose(h, h_ref, rtol=1e-13, atol=1e-18)
    np.testing.assert_allclose(lnp, lnp_ref, rtol=1e-13, atol=1e-15)
    sums = PairSums.zeros(len(log_q), len(lam))
    h2, lnp2 = sweep(system, log_q, sums, chunk_pairs=chunk_pairs)
    np.testing.assert_allclose(h2, h_ref, rtol=1e-13, atol=1e-18)
    np.testing.assert_array_equal(lnp2, lnp)
    np.testing.assert_allclose(sums.by_class, cls_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sums.by_seeker, seek_ref, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("savings", [False, True])
def test_sweep_does_not_depend_on_the_thread_count(savings):
    """The plain sweep and the savings pass (whose chunks run in parts) give the same bits on 1 and n threads."""
    from numba import get_num_threads, set_num_threads

    matching, lam, log_q = random_lists(7, n_od=400, n_classes=200)
    system = System.build(None, matching, lam, PredictConfig())
    before = get_num_threads()
    try:
        results = []
        for threads in (1, before):
            set_num_threads(threads)
            sums = PairSums.zeros(200, 400) if savings else None
            out = sweep(system, log_q, sums, chunk_pairs=50)
            results.append(out + ((sums.by_class, sums.by_seeker) if savings else ()))
    finally:
        set_num_threads(before)
    for a, b in zip(*results, strict=True):
        np.testing.assert_array_equal(a, b)


def test_model_sweep_on_a_real_matching_equals_the_reference():
    model = make_instance(seed=3, size=6, n_od=50, max_pickup_m=3000, max_detour_m=3000).model()
    rng = np.random.default_rng(0)
    log_q = np.log1p(-rng.uniform(0, 0.3, model.space.n_classes))
    h_ref, lnp_ref, _, _ = reference_sweep(model.matching, model.rates.rate_per_s, log_q)
    h, lnp = sweep(model.system, log_q)
    np.testing.assert_allclose(h, h_ref, rtol=1e-13, atol=1e-18)
    np.testing.assert_allclose(lnp, lnp_ref, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("seed", range(6))
def test_group_counts_equal_a_brute_force_count(seed):
    """``count_at_most``: per (group, threshold) the number of the group's values <= threshold, with ties,
    thresholds on, between and outside the values, infinities and NaN; and whether it needed a search."""
    from rpbench.predict.kernels import count_at_most

    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 9, 12)
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    a = np.concatenate([np.sort(rng.integers(-5, 6, k).astype(np.float64)) for k in sizes])  # many ties
    u = rng.integers(0, len(sizes), 400).astype(np.int64)
    threshold = rng.integers(-7, 8, 400) + rng.choice([0.0, 0.5], 400)
    threshold[::37] = np.inf
    threshold[5::37] = -np.inf
    threshold[9::37] = np.nan
    got = [count_at_most(a, start[g], sizes[g], t) for g, t in zip(u, threshold, strict=True)]
    values = [a[start[g] : start[g] + sizes[g]] for g in u]
    assert [k for k, _ in got] == [int(np.sum(v <= t)) for v, t in zip(values, threshold, strict=True)]
    assert [s for _, s in got] == [int(v[0] <= t < v[-1]) for v, t in zip(values, threshold, strict=True)]


def reference_runs(from_b, to_b, solo_b, group_dest, group_d_oa, a, start, size, d_lim, keep_nonpositive, min_feasible):
    """The runs of :func:`feasible_runs` cell by cell, counting by comparison (no binary search)."""
    runs = []
    for r, l_b in enumerate(solo_b):
        fofo = []
        for u, d_a in enumerate(group_dest):
            values = a[start[u] : start[u] + size[u]]
            d_ba, d_ab, d_oa = from_b[r, d_a], to_b[r, d_a], group_d_oa[u]
            f_ok = d_oa + d_ab - l_b <= d_lim
            g_f, g_l, thr_l = l_b - d_oa - d_ab, -d_ba, d_lim - l_b - d_ba
            if min_feasible:
                take_l, take_f, folo_pref = (not f_ok) or g_l > g_f, f_ok, g_l > g_f
            else:
                take_l = not g_f >= g_l
                take_f, folo_pref = (not take_l) and f_ok, False

            def count(t, values=values):
                return int(np.sum(values <= t))

            if take_l:
                hi = count(np.minimum(thr_l, np.inf if keep_nonpositive else np.nextafter(g_l, -np.inf)))
                if hi:
                    runs.append((r, start[u], hi, g_l, np.float32(l_b), np.float32(0.0)))
            if take_f:
                lo = count(thr_l) if folo_pref else 0
                hi = count(np.inf if keep_nonpositive else np.nextafter(g_f, -np.inf))
                if hi > lo:
                    fofo.append((r, start[u] + lo, hi - lo, g_f, np.float32(d_oa), np.float32(-g_f)))
        runs += fofo
    return runs


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("keep_nonpositive", [False, True])
@pytest.mark.parametrize("min_feasible", [True, False])
def test_feasible_runs_equal_a_cell_by_cell_reference(seed, keep_nonpositive, min_feasible):
    """``feasible_runs`` against the cell-by-cell reference: the same runs in the same order (row; FOLO
    then FOFO; group), on coarse distances with ties, thresholds exactly met and unreachable nodes (inf),
    and outputs too short (it asks for longer ones)."""
    from rpbench.predict.kernels import feasible_runs

    rng = np.random.default_rng(seed)
    n_nodes, m, n_u = 9, 5, 6
    dist = rng.integers(0, 8, (n_nodes, n_nodes)).astype(np.float64)
    dist[rng.random(dist.shape) < 0.05] = np.inf
    d_b = rng.integers(0, n_nodes, m)
    from_b, to_b = dist[d_b], np.ascontiguousarray(dist.T)[d_b]
    solo_b = rng.integers(1, 9, m).astype(np.float64)
    group_dest = np.sort(rng.choice(n_nodes, n_u, replace=False)).astype(np.int64)
    group_d_oa = rng.integers(0, 8, n_u).astype(np.float64)
    size = rng.integers(1, 7, n_u).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(size)[:-1]]).astype(np.int64)
    a = np.concatenate([np.sort(rng.integers(-9, 3, k).astype(np.float64)) for k in size])
    d_lim = 4.0
    args = (from_b, to_b, solo_b, group_dest, group_d_oa, a, start, size, d_lim, keep_nonpositive, min_feasible)
    want = reference_runs(*args)
    assert want, "the instance should have runs"
    short = [
        np.empty(len(want) - 1, dtype=t) for t in (np.int64, np.int64, np.int64, np.float64, np.float32, np.float32)
    ]
    assert feasible_runs(*args, *short) == (-1, 0)
    out = [np.empty(2 * m * n_u, dtype=t) for t in (np.int64, np.int64, np.int64, np.float64, np.float32, np.float32)]
    k, _ = feasible_runs(*args, *out)
    got = list(zip(*(col[:k].tolist() for col in out), strict=True))
    assert got == [tuple(float(x) if i >= 3 else int(x) for i, x in enumerate(run)) for run in want]


def reference_pair_values(geometry: ListGeometry, seeker: np.ndarray, cls: np.ndarray):
    """E, shared and seeker detour of each (seeker, class) pair, written from the definitions: the pair lies
    in the FOLO run of its (seeker, d_A) cell when FOLO is taken there and its ``a`` is within that run's
    bound (the bound :func:`feasible_runs` counts with), else in the FOFO run."""
    g, dist = geometry, geometry.distances()
    o, d_b, l_b = g.origin[seeker], g.destination[seeker], g.solo_m[seeker]
    h, d_a = g.class_head[cls], g.class_dest[cls]
    a = dist[h, o] - g.class_rest_m[cls]
    d_ba, d_ab, d_oa = dist[d_b, d_a], dist[d_a, d_b], dist[o, d_a]
    f_ok = d_oa + d_ab - l_b <= g.d_lim
    g_f, g_l, thr_l = l_b - d_oa - d_ab, -d_ba, g.d_lim - l_b - d_ba
    take_l = (~f_ok | (g_l > g_f)) if g.min_feasible else ~(g_f >= g_l)
    cut_l = np.full(len(a), np.inf) if g.keep_nonpositive else np.nextafter(g_l, -np.inf)
    with np.errstate(invalid="ignore"):
        folo = take_l & (a <= np.fmin(thr_l, cut_l)) & ~np.isnan(thr_l)
    e = np.where(folo, g_l - a, g_f - a).astype(np.float32)
    shared = np.where(folo, l_b, d_oa).astype(np.float32)
    detour = np.where(folo, 0.0, -g_f).astype(np.float32)
    return e, shared, detour


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("keep_nonpositive", [False, True])
@pytest.mark.parametrize("min_feasible", [True, False])
def test_pair_values_equal_a_reference_bit_for_bit(seed, keep_nonpositive, min_feasible):
    """:func:`pair_values` (what the savings pass computes per pair) against the reference, on every
    (seeker, class) pair of a random geometry with ties, exactly met thresholds and unreachable nodes."""
    rng = np.random.default_rng(seed)
    n_od, n_classes = 30, 25
    geometry = random_geometry(
        rng, n_od, n_classes, unreachable=0.05, keep_nonpositive=keep_nonpositive, min_feasible=min_feasible
    )
    off = np.arange(n_od + 1, dtype=np.int64) * n_classes
    cls = np.tile(np.arange(n_classes, dtype=np.int32), n_od)
    got = geometry.values(off, cls, 0, n_od)
    want = reference_pair_values(geometry, np.repeat(np.arange(n_od), n_classes), cls)
    for name, x, y in zip(("E", "shared", "detour"), got, want, strict=True):
        assert x.dtype == np.float32
        np.testing.assert_array_equal(x.view(np.uint32), y.view(np.uint32), err_msg=name)
    s0, s1 = 7, 12  # a range of seekers: the outputs start at its first pair
    part = geometry.values(off, cls[off[s0] : off[s1]], s0, s1)
    for x, y in zip(part, got, strict=True):
        np.testing.assert_array_equal(x, y[off[s0] : off[s1]])


def test_savings_pass_uses_the_pair_values_of_the_lists():
    """The savings pass's sums on a real model equal sums over :meth:`Matching.arrays`' values (which
    test_match_sets checks against a brute-force POOL), all with E > 0."""
    model = make_instance(seed=3, size=6, n_od=50, max_pickup_m=3000, max_detour_m=3000).model()
    rng = np.random.default_rng(1)
    log_q = np.log1p(-rng.uniform(0, 0.3, model.space.n_classes))
    _, _, cls_ref, seek_ref = reference_sweep(model.matching, model.rates.rate_per_s, log_q)
    sums = PairSums.zeros(model.space.n_classes, len(model.rates))
    sweep(model.system, log_q, sums)
    np.testing.assert_allclose(sums.by_class, cls_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sums.by_seeker, seek_ref, rtol=1e-12, atol=1e-12)
    assert np.all(model.matching.saving_m > 0)
