"""Anderson mixing with an updated QR factorisation against the textbook step (stacked history, ``lstsq``)."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from rpbench.predict.anderson import AndersonMixing


class StackedAnderson:
    """Reference: re-stack the last ``depth`` differences and solve with numpy's ``lstsq`` every step."""

    def __init__(self, depth):
        self.depth = depth
        self.restart()

    def restart(self):
        self.x_prev = self.f_prev = None
        self.dx, self.df = [], []

    def step(self, x, f, damped, beta):
        if self.x_prev is not None:
            self.dx.append(x - self.x_prev)
            self.df.append(f - self.f_prev)
            del self.dx[: -self.depth], self.df[: -self.depth]
        self.x_prev, self.f_prev = x, f
        if not self.df:
            return damped
        df = np.stack(self.df, axis=1)
        gamma, *_ = np.linalg.lstsq(df, f, rcond=None)
        return damped - (np.stack(self.dx, axis=1) + beta * df) @ gamma


# One step of a history: "random" residual, a residual whose difference repeats (times 2) the last one
# (collinear ΔF), the previous residual again (a zero difference), or a restart before the step.
MOVES = st.lists(st.sampled_from(["random", "collinear", "repeat", "restart"]), min_size=1, max_size=25)


def _residual(move, rng, prev_f, prev_df, n):
    if move == "collinear" and prev_f is not None and prev_df is not None:
        return prev_f + 2.0 * prev_df
    if move == "repeat" and prev_f is not None:
        return prev_f.copy()
    return rng.standard_normal(n)


@settings(max_examples=60, deadline=None)
@given(depth=st.integers(1, 6), moves=MOVES, seed=st.integers(0, 2**32 - 1))
# Found by hypothesis: a run of collinear differences, then an independent one (Q lost orthogonality
# by 3e-7 when the dependent remainder was normalised as it was).
@example(depth=3, moves=["random"] * 3 + ["collinear"] * 4 + ["random"], seed=1)
def test_steps_match_the_stacked_least_squares(depth, moves, seed):
    rng = np.random.default_rng(seed)
    n = 200
    mixing, reference = AndersonMixing(depth), StackedAnderson(depth)
    prev_f = prev_df = None
    for i, move in enumerate(moves):
        if move == "restart":
            mixing.restart()
            reference.restart()
            prev_f = prev_df = None
        x = rng.standard_normal(n)
        f = _residual(move, rng, prev_f, prev_df, n)
        beta = 0.5 if i < 10 else 0.25  # β may change within a history
        got = mixing.step(x, f, beta * f, beta)
        want = reference.step(x, f, beta * f, beta)
        scale = max(1.0, float(np.abs(want).max()))
        assert np.abs(got - want).max() <= 1e-9 * scale, (i, move)
        if mixing.size:
            q = mixing._q[:, : mixing.size]
            assert np.abs(q.T @ q - np.eye(mixing.size)).max() <= 1e-12, (i, move)
        prev_df = None if prev_f is None else f - prev_f
        prev_f = f


@pytest.mark.parametrize("depth", [1, 3, 5])
def test_factorisation_stays_orthonormal_and_reproduces_the_differences(depth):
    rng = np.random.default_rng(7)
    n = 500
    mixing = AndersonMixing(depth)
    fs = [rng.standard_normal(n) for _ in range(12)]
    for f in fs:
        mixing.step(rng.standard_normal(n), f, 0.5 * f, 0.5)
    m = mixing.size
    assert m == min(depth, len(fs) - 1)
    q, r = mixing._q[:, :m], mixing._r[:m, :m]
    np.testing.assert_allclose(q.T @ q, np.eye(m), atol=1e-12)
    assert np.allclose(np.tril(r, -1), 0.0)
    differences = np.stack([b - a for a, b in zip(fs[-m - 1 : -1], fs[-m:], strict=True)], axis=1)
    np.testing.assert_allclose(q @ r, differences, atol=1e-12)


def test_a_non_finite_solve_restarts_with_the_damped_step():
    mixing = AndersonMixing(3)
    x = np.zeros(4)
    f = np.ones(4)
    mixing.step(x, f, 0.5 * f, 0.5)
    bad = np.array([np.nan, 1.0, 1.0, 1.0])
    assert np.array_equal(mixing.step(x + 1.0, bad, 0.5 * bad, 0.5), 0.5 * bad, equal_nan=True)
    assert mixing.size == 0
