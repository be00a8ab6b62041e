"""Bootstrap intervals and paired tests on data small enough to check by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rpbench.report.leaderboard import (
    RATIO_OF_MEANS,
    Bootstrap,
    draw_indices,
    interval,
    leaderboard,
    paired,
    resampled_means,
)


def units(values: dict[str, list[list[float]]], kpi: str = "total_saving_km") -> pd.DataFrame:
    """A units table: per run a days x seeds matrix of one KPI."""
    rows = []
    for run, matrix in values.items():
        for d, row in enumerate(matrix):
            for s, v in enumerate(row):
                rows.append({"day": f"2017-05-{d + 1:02d}", "seed": s, "run": run, "kpi": kpi, "value": v})
    return pd.DataFrame(rows)


def test_two_days_one_seed_resample_to_their_three_means():
    """Days {0, 1}: a resample's mean is 0, 0.5 or 1 with chances 1/4, 1/2, 1/4."""
    boot = Bootstrap(resamples=20_000, seed=1)
    means = resampled_means(np.array([[0.0], [1.0]]), draw_indices(2, 1, boot))
    assert set(np.round(means, 9)) == {0.0, 0.5, 1.0}
    assert np.mean(means == 0.5) == pytest.approx(0.5, abs=0.02)
    assert interval(means, 0.95) == (0.0, 1.0)  # 25 % mass at each end: the 2.5 % and 97.5 % points


def test_seeds_are_resampled_within_their_day():
    """One day, seeds {0, 2}: the day is always drawn, its seeds resampled: means 0, 1, 2 at 1/4, 1/2, 1/4."""
    means = resampled_means(np.array([[0.0, 2.0]]), draw_indices(1, 2, Bootstrap(resamples=20_000)))
    assert set(np.round(means, 9)) == {0.0, 1.0, 2.0}
    assert np.mean(means == 1.0) == pytest.approx(0.5, abs=0.02)


def test_a_constant_metric_has_a_point_interval_and_the_draws_are_seeded():
    board = leaderboard(units({"a": [[3.0, 3.0]] * 4}), ["a"], ["total_saving_km"], Bootstrap(resamples=200))
    (row,) = board.itertuples()
    assert (row.mean, row.ci_low, row.ci_high, row.days, row.seeds) == (3.0, 3.0, 3.0, 4, 2)
    table = units({"a": [[1.0, 2.0], [5.0, 3.0], [0.0, 4.0]]})
    first = leaderboard(table, ["a"], ["total_saving_km"], Bootstrap(seed=7))
    assert first.equals(leaderboard(table, ["a"], ["total_saving_km"], Bootstrap(seed=7)))
    assert not first.equals(leaderboard(table, ["a"], ["total_saving_km"], Bootstrap(seed=8)))


def test_ratio_of_means_is_not_the_mean_of_ratios():
    table = units({"fl": [[1.0], [9.0]], "bound": [[2.0], [10.0]]})
    ratios = units({"fl": [[0.5], [0.9]], "bound": [[1.0], [1.0]]}, kpi="competitive_ratio_bound")
    board = leaderboard(pd.concat([table, ratios]), ["fl", "bound"], ["total_saving_km", "competitive_ratio_bound"],
                        Bootstrap(resamples=500))  # fmt: skip
    cell = board.set_index(["run", "kpi"])["mean"]
    assert cell[("fl", "competitive_ratio_bound")] == pytest.approx(0.7)  # mean of ratios
    assert cell[("fl", RATIO_OF_MEANS)] == pytest.approx(10 / 12)  # ratio of means


def test_paired_differences_and_the_exact_wilcoxon_p():
    """Five days, A above B on every one: the exact two-sided signed-rank p is 2 / 2^5 = 0.0625."""
    b = [[1.0], [2.0], [3.0], [4.0], [5.0]]
    a = [[1.5], [2.1], [4.0], [4.3], [5.2]]
    (row,) = paired(units({"a": a, "b": b}), ["a", "b"], ["total_saving_km"], Bootstrap(resamples=500)).itertuples()
    assert row.mean_diff == pytest.approx(np.mean([0.5, 0.1, 1.0, 0.3, 0.2]))
    assert row.wilcoxon_p == pytest.approx(0.0625)
    assert (row.days_a_above, row.days_a_below, row.days_tied) == (5, 0, 0)
    assert 0.1 <= row.ci_low <= row.mean_diff <= row.ci_high <= 1.0


def test_the_pairing_is_kept():
    """B = A + 1 on every unit, whatever the spread of A: the difference's interval is exactly [-1, -1]."""
    a = [[0.0, 10.0], [50.0, 3.0], [7.0, 7.0]]
    b = [[v + 1.0 for v in row] for row in a]
    (row,) = paired(units({"a": a, "b": b}), ["a", "b"], ["total_saving_km"], Bootstrap(resamples=300)).itertuples()
    assert (row.mean_diff, row.ci_low, row.ci_high) == (-1.0, -1.0, -1.0)


@pytest.mark.parametrize("n", [3, 5, 7])
def test_the_paired_table_states_the_smallest_p_its_days_allow(n):
    """The report's sentence gives the p SciPy's exact test returns when every day goes one way."""
    from scipy.stats import wilcoxon

    from rpbench.report.evaluation import smallest_p_text

    smallest = float(wilcoxon(np.arange(1.0, n + 1.0)).pvalue)
    assert smallest == pytest.approx(2.0 / 2.0**n)
    assert f"With {n} days the exact test's smallest p is 2 / 2^{n} = {smallest:.3g}" in smallest_p_text(n, "days")
    assert smallest_p_text(0, "days") == ""
