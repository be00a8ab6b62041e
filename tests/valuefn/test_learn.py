"""Policy evaluation on hand-made transitions: the exact solution and online TD(0), checked on paper.

The three-cell example (one time bin, so a state is a cell; discount per transition as given)::

    t = 0:  s0 -> s1   r = 100, γ = 0.5
    t = 1:  s1 -> s2   r = 200, γ = 0.5
    t = 2:  s2 -> end  r = 300
    t = 3:  s1 -> end  r = 40          (s1 has two outgoing transitions: their average)

Exact: V2 = 300; V1 = ((200 + 0.5·300) + 40) / 2 = 195; V0 = 100 + 0.5·195 = 197.5.
TD(0) with α = 0.5 from V = 0, in time order: V0 = 0.5·100 = 50; V1 = 0.5·200 = 100; V2 = 0.5·300 = 150;
V1 = 100 + 0.5·(40 - 100) = 70.  A second pass: V0 = 50 + 0.5·(100 + 0.5·70 - 50) = 92.5;
V1 = 70 + 0.5·(200 + 0.5·150 - 70) = 172.5; V2 = 150 + 0.5·(300 - 150) = 225; V1 = 172.5 + 0.5·(40 - 172.5) = 106.25.
(Powers of two: every figure is exact in floating point.)
"""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.valuefn.cells import Grid
from rpbench.valuefn.learn import LEARN_METHODS, evaluate_policy, fill_unvisited
from rpbench.valuefn.transitions import Transitions


def grid(n_cells: int = 3, n_bins: int = 1) -> Grid:
    return Grid(cell_m=1000.0, bin_s=100.0, n_bins=n_bins, node_cell=np.arange(n_cells), n_cells=n_cells)


def transitions(rows: list[tuple[int, int, float, float, float]]) -> Transitions:
    """Rows (state, next state or -1, reward, γ, t_s)."""
    state, nxt, reward, gamma, t = (np.array(c) for c in zip(*rows, strict=True))
    return Transitions(state.astype(np.int64), nxt.astype(np.int64), reward.astype(float), gamma.astype(float), t)


#: The module docstring's example, deliberately not in time order (TD(0) must sort by time).
CHAIN = transitions(
    [
        (1, -1, 40.0, 0.0, 3.0),
        (0, 1, 100.0, 0.5, 0.0),
        (2, -1, 300.0, 0.0, 2.0),
        (1, 2, 200.0, 0.5, 1.0),
    ]
)


def test_exact_solves_the_bellman_equation_of_the_chain():
    values, visits = evaluate_policy(CHAIN, grid(), method="exact")
    assert values.shape == visits.shape == (3, 1)
    assert values[:, 0].tolist() == [197.5, 195.0, 300.0]
    assert visits[:, 0].tolist() == [1, 2, 1]
    assert evaluate_policy(CHAIN, grid())[0].tolist() == values.tolist()  # exact is the default


def test_one_td_pass_gives_the_hand_computed_values():
    values, visits = evaluate_policy(CHAIN, grid(), method="td", learning_rate=0.5, epochs=1)
    assert values[:, 0].tolist() == [50.0, 70.0, 150.0]
    assert visits[:, 0].tolist() == [1, 2, 1]
    two, _ = evaluate_policy(CHAIN, grid(), method="td", learning_rate=0.5, epochs=2)
    assert two[:, 0].tolist() == [92.5, 106.25, 225.0]


def test_td_with_a_small_step_and_many_passes_approaches_exact():
    """Constant-step TD(0) hovers around the exact solution, the closer the smaller the step."""
    exact = evaluate_policy(CHAIN, grid())[0][:, 0]
    coarse = evaluate_policy(CHAIN, grid(), method="td", learning_rate=0.01, epochs=5000)[0][:, 0]
    fine = evaluate_policy(CHAIN, grid(), method="td", learning_rate=0.002, epochs=20000)[0][:, 0]
    assert np.abs(fine - exact).max() < 0.5
    assert np.abs(fine - exact).max() < np.abs(coarse - exact).max() < 5.0


def test_exact_solves_a_cycle_not_just_a_chain():
    """s0 -> s1 (r 10, γ 0.5); s1 -> s0 (r 20, γ 0.5) or s1 -> end (r 0): V0 = 10 + V1/2, V1 = 10 + V0/4,
    so V0 = 120/7 and V1 = 100/7 (a back-substitution would not get there)."""
    cycle = transitions([(0, 1, 10.0, 0.5, 0.0), (1, 0, 20.0, 0.5, 1.0), (1, -1, 0.0, 0.0, 2.0)])
    values, _ = evaluate_policy(cycle, grid())
    assert values[:2, 0] == pytest.approx([120 / 7, 100 / 7], rel=1e-12)
    assert values[2, 0] == pytest.approx((120 / 7 + 2 * 100 / 7) / 3, rel=1e-12)  # unvisited: the bin's mean


def test_unvisited_states_hold_their_bins_visit_weighted_mean():
    """The chain on cells 0-2 of bin 0 of a 4-cell, 2-bin grid: cell 3 of bin 0 was never left, it reads
    (197.5·1 + 195·2 + 300·1) / 4; bin 1 has no visit at all and reads 0."""
    g = grid(n_cells=4, n_bins=2)
    moved = Transitions(
        CHAIN.state * 2,
        np.where(CHAIN.next_state >= 0, CHAIN.next_state * 2, -1),
        CHAIN.reward_m,
        CHAIN.gamma,
        CHAIN.t_s,
    )
    for method in LEARN_METHODS:
        values, visits = evaluate_policy(moved, g, method=method, learning_rate=0.5, epochs=1)
        assert visits.tolist() == [[1, 0], [2, 0], [1, 0], [0, 0]]
        assert values[:, 1].tolist() == [0.0] * 4
        mean = (values[0, 0] + 2 * values[1, 0] + values[2, 0]) / 4
        assert values[3, 0] == pytest.approx(mean)
    assert evaluate_policy(moved, g)[0][3, 0] == (197.5 + 390.0 + 300.0) / 4
    # visited states keep their value; each unvisited one gets its column's visit-weighted mean
    filled = fill_unvisited(np.array([[5.0, 7.0], [1.0, 9.0], [0.0, 0.0]]), np.array([[3, 0], [1, 2], [0, 0]]))
    assert filled.tolist() == [[5.0, 9.0], [1.0, 9.0], [4.0, 9.0]]


def test_no_transitions_give_zero_and_an_unknown_method_is_refused():
    empty = transitions([(0, -1, 0.0, 0.0, 0.0)])
    empty = Transitions(*(getattr(empty, f)[:0] for f in ("state", "next_state", "reward_m", "gamma", "t_s")))
    for method in LEARN_METHODS:
        values, visits = evaluate_policy(empty, grid(), method=method)
        assert values.tolist() == [[0.0]] * 3 and visits.tolist() == [[0]] * 3
    with pytest.raises(ValueError, match="method 'mc' unknown; expected one of exact, td"):
        evaluate_policy(CHAIN, grid(), method="mc")
