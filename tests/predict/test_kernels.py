"""The compiled sweeps against the numpy formulation they replaced (segmented log sums, exp, bincount)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.predict._arrays import segment_exclusive_cumsum, segment_sums
from rpbench.predict.config import PredictConfig
from rpbench.predict.fixed_point import PairSums, System, sweep
from rpbench.predict.match_sets import Matching

from .conftest import make_instance


def random_lists(seed: int, n_od: int = 40, n_classes: int = 30, empty_share: float = 0.2, block_classes: int = 20):
    """Seeker lists of random lengths (some empty) over random classes, with random per-pair distances."""
    rng = np.random.default_rng(seed)
    lens = rng.integers(1, 12, n_od) * (rng.random(n_od) > empty_share)
    off = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
    cls = np.concatenate([rng.choice(n_classes, k, replace=False) for k in lens]).astype(np.int32)
    n = len(cls)
    cols = [rng.uniform(0, 3000, n).astype(np.float32) for _ in range(3)]
    matching = Matching.from_lists(off, cls, cols[0], cols[1], cols[2], n_classes=n_classes, limit=block_classes)
    lam = rng.uniform(0, 0.01, n_od) * (rng.random(n_od) > 0.1)          # some λ = 0
    log_q = np.log1p(-rng.uniform(0, 0.9, n_classes))
    return matching, lam, log_q


def reference_sweep(matching: Matching, lam: np.ndarray, log_q: np.ndarray):
    """H_c, log(1 - p_s) and the pair sums, written the numpy way (one exp per pair)."""
    off, cls = matching.seeker_off, matching.cls
    owner = np.repeat(np.arange(len(lam)), np.diff(off))
    v = log_q[cls]
    with np.errstate(divide="ignore"):
        weight = lam[owner] * np.exp(segment_exclusive_cumsum(v, off))   # λ_s Π_{c' ≻ c} Q_c'
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
    for a, b in zip(*results):
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
    thresholds on, between and outside the values, infinities and NaN; and how many needed a search."""
    from rpbench.predict.kernels import count_at_most

    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 9, 12)
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    a = np.concatenate([np.sort(rng.integers(-5, 6, k).astype(np.float64)) for k in sizes])   # many ties
    u = rng.integers(0, len(sizes), 400).astype(np.int64)
    threshold = rng.integers(-7, 8, 400) + rng.choice([0.0, 0.5], 400)
    threshold[::37] = np.inf
    threshold[5::37] = -np.inf
    threshold[9::37] = np.nan
    out = np.empty(len(u), dtype=np.int64)
    searched = count_at_most(a, start, sizes.astype(np.int64), u, threshold, out)
    values = [a[start[g]:start[g] + sizes[g]] for g in u]
    want = [int(np.sum(v <= t)) for v, t in zip(values, threshold)]
    assert out.tolist() == want
    assert searched == sum(bool(v[0] <= t < v[-1]) for v, t in zip(values, threshold))
