"""The trip-packing LP shortcut (rpbench.backends.unique): an answer only for a provably unique optimum."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rpbench.backends import SolveOptions, get_backend
from rpbench.backends.highs import highs_settings, kept_instance
from rpbench.backends.unique import unique_optimum
from rpbench.bench import synthetic
from rpbench.model import TripPackingModel
from rpbench.sim.ties import canonicalize

from .brute import MAX_COLS

pytest.importorskip("highspy")
SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)


def optima(model) -> list[np.ndarray]:
    """Every optimal 0/1 point of a tiny model, as sorted column indices."""
    n = model.n_cols
    X = ((np.arange(2**n)[:, None] >> np.arange(n)) & 1).astype(np.int64)
    ok = ((X @ model.incidence().T.toarray().astype(np.int64)) <= 1).all(axis=1)
    value = X[ok] @ model.values
    return [np.flatnonzero(x) for x in X[ok][value == value.max()]]


def lp_answer(model):
    return unique_optimum(model, kept_instance(highs_settings(SolveOptions(), None, relax=True), role="test"))


VALUES = st.integers(-6, 12)


@st.composite
def packings(draw, values=VALUES):
    R, V = draw(st.integers(1, 5)), draw(st.integers(1, 4))
    singles = [(r, -1, v) for r in range(R) for v in range(V) if draw(st.integers(0, 2)) == 0]
    pairs = [(a, b, v) for a in range(R) for b in range(a + 1, R) for v in range(V) if draw(st.integers(0, 4)) == 0]
    cols = sorted(singles + pairs)[:MAX_COLS]
    vals = draw(st.lists(values, min_size=len(cols), max_size=len(cols)))
    return TripPackingModel(R, V, [c[2] for c in cols], [c[0] for c in cols], [c[1] for c in cols], vals)


@settings(max_examples=300, **SETTINGS)
@given(packings())
def test_an_answer_is_the_only_optimum_and_ties_get_none(model):
    # Small integer values make ties common: the shortcut must never answer one.
    best = optima(model)
    got = lp_answer(model)
    if len(best) > 1:
        assert got is None
    elif got is not None:
        assert np.array_equal(np.sort(got), best[0])


@settings(max_examples=150, **SETTINGS)
@given(packings(values=st.integers(-(10**6), 10**7)))
def test_the_shortcut_gives_the_mips_plan_on_tie_free_models(model):
    # Wide values: optima are almost always unique, and then the plan must be the full MIP's exactly.
    backend = get_backend("highs")
    fast, mip = backend.solve(model, SolveOptions()), backend.solve(model, SolveOptions(method="mip"))
    assert np.array_equal(fast.chosen, mip.chosen)
    assert (fast.status, fast.objective, fast.bound, fast.gap) == (mip.status, mip.objective, mip.bound, mip.gap)
    if fast.unique:
        assert len(optima(model)) == 1


@pytest.mark.parametrize("size", [(12, 6), (60, 30), (200, 100)])
@pytest.mark.parametrize("seed", range(4))
def test_synthetic_rounds_get_the_mips_plan(size, seed):
    model = synthetic.trip_packing(*size, seed=seed)
    backend = get_backend("highs")
    fast, mip = backend.solve(model, SolveOptions()), backend.solve(model, SolveOptions(method="mip"))
    assert np.array_equal(fast.chosen, mip.chosen) and fast.objective == mip.objective


def test_most_synthetic_rounds_are_proven_unique():
    # Not vacuous: the proof often succeeds (on the denser synthetic models the LP is fractional more often
    # than in simulation rounds, where 97 % of the full day's rounds are proven).
    proven = [lp_answer(synthetic.trip_packing(20, 10, seed=s)) is not None for s in range(10)]
    assert sum(proven) >= 6


def test_disjoint_trips_and_all_negative_values():
    disjoint = TripPackingModel(3, 3, [0, 1, 2], [0, 1, 2], [-1, -1, -1], [5, 7, -2])
    assert list(lp_answer(disjoint)) == [0, 1]
    assert list(lp_answer(TripPackingModel(2, 1, [0, 0], [0, 1], [-1, -1], [-3, -1]))) == []
    assert lp_answer(TripPackingModel(2, 2, [0, 1], [0, 1], [-1, -1], [4, 0])) is None  # zero value: a tie


def test_a_unique_optimum_needs_no_tie_repair():
    model = synthetic.trip_packing(20, 10, seed=0)
    sol = get_backend("highs").solve(model, SolveOptions())
    assert sol.unique
    assert canonicalize(model, sol) == (sol, 0)
