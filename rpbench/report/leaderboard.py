"""An evaluation's statistics over its (day, seed) runs: means with bootstrap intervals, and paired comparisons.

The units of an evaluation are its runs, one per (day, seed).  Days are the independent draws (each day
its own demand); seeds within a day share that day's orders and differ in the sample, the patience draws
and the fleet's starting nodes.  Hence:

* **Interval of a mean** — a two-stage (cluster) bootstrap: resample the days with replacement, then
  within each drawn day its seeds with replacement, and take the mean of the drawn values; the interval is
  the percentile interval of those means (``level``, ``resamples`` and the generator's seed stated in the
  protocol).  An undated scenario's clusters are its seeds, one value each.
* **Paired difference** of two strategies on one metric — the same bootstrap of the per-unit difference
  A - B, so the pairing (same day, same seed) is kept; and the Wilcoxon signed-rank test (two-sided,
  exact for small samples) of the per-day mean differences, days being the independent units, with the
  sign count (days where A is above B, below it, tied).
* **Ratios** — the competitive ratio of a run is its saving over the bound's on the same unit; its mean
  over units is a *mean of ratios*.  The *ratio of means* (mean saving over mean bound saving) weights big
  days more; both are reported, by those names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

#: The row of the leaderboard for a run's mean saving over the bound's mean saving (a ratio of means).
RATIO_OF_MEANS = "saving_ratio_of_means"


@dataclass(frozen=True)
class Bootstrap:
    """How intervals are drawn: resamples, the generator's seed, the coverage."""

    resamples: int = 2000
    seed: int = 0
    level: float = 0.95


def unit_matrix(units: pd.DataFrame, run: str, kpi: str) -> np.ndarray:
    """The values of ``run``'s ``kpi`` as a days x seeds matrix (``units`` columns day, seed, run, kpi,
    value; an undated evaluation's day is empty: each seed becomes its own cluster)."""
    sel = units[(units["run"] == run) & (units["kpi"] == kpi)]
    if sel["day"].eq("").all():
        return sel.sort_values("seed")["value"].to_numpy(dtype=float)[:, None]
    wide = sel.pivot(index="day", columns="seed", values="value").sort_index()
    return wide.to_numpy(dtype=float)


def draw_indices(days: int, seeds: int, boot: Bootstrap) -> tuple[np.ndarray, np.ndarray]:
    """The bootstrap's draws: days (resamples x days) and, within each drawn day, seeds (resamples x days x
    seeds); one generator, so every statistic of an evaluation uses the same draws."""
    rng = np.random.default_rng(boot.seed)
    day_idx = rng.integers(0, days, size=(boot.resamples, days))
    seed_idx = rng.integers(0, seeds, size=(boot.resamples, days, seeds))
    return day_idx, seed_idx


def resampled_means(values: np.ndarray, draws: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The mean of each bootstrap resample of the days x seeds matrix ``values``."""
    day_idx, seed_idx = draws
    return values[day_idx[:, :, None], seed_idx].mean(axis=(1, 2))


def interval(samples: np.ndarray, level: float) -> tuple[float, float]:
    """The percentile interval of bootstrap ``samples`` at coverage ``level``."""
    tail = (1.0 - level) / 2.0
    low, high = np.quantile(samples, [tail, 1.0 - tail])
    return float(low), float(high)


def leaderboard(units: pd.DataFrame, runs: Sequence[str], kpis: Sequence[str], boot: Bootstrap) -> pd.DataFrame:
    """Per run and metric: the mean over units, its interval, and the number of days and seeds.  With a bound
    run, also each run's :data:`RATIO_OF_MEANS` (mean saving / mean bound saving) with its interval."""
    rows = []
    for run in runs:
        for kpi in kpis:
            values = unit_matrix(units, run, kpi)
            if not values.size or np.isnan(values).any():
                continue  # a run without this metric (an offline run's response rate) or with gaps
            draws = draw_indices(values.shape[0], values.shape[1], boot)
            low, high = interval(resampled_means(values, draws), boot.level)
            rows.append(_row(run, kpi, values, low, high))
        if "bound" in runs and run != "bound":
            saving, bound = unit_matrix(units, run, "total_saving_km"), unit_matrix(units, "bound", "total_saving_km")
            if saving.size and saving.shape == bound.shape and not np.isnan(saving).any():
                draws = draw_indices(saving.shape[0], saving.shape[1], boot)
                ratio = resampled_means(saving, draws) / resampled_means(bound, draws)
                low, high = interval(ratio, boot.level)
                row = _row(run, RATIO_OF_MEANS, saving, low, high)
                row["mean"] = float(saving.mean() / bound.mean())
                rows.append(row)
    return pd.DataFrame(rows, columns=["run", "kpi", "mean", "ci_low", "ci_high", "days", "seeds"])


def _row(run: str, kpi: str, values: np.ndarray, low: float, high: float) -> dict:
    return {
        "run": run,
        "kpi": kpi,
        "mean": float(values.mean()),
        "ci_low": low,
        "ci_high": high,
        "days": values.shape[0],
        "seeds": values.shape[1],
    }


def paired(units: pd.DataFrame, runs: Sequence[str], kpis: Sequence[str], boot: Bootstrap) -> pd.DataFrame:
    """For every ordered pair (a, b) of ``runs`` (a before b) and metric: the mean of a - b over units with its
    interval, the Wilcoxon signed-rank p-value over the per-day mean differences, and the sign counts."""
    from scipy.stats import wilcoxon

    rows = []
    draws: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}  # every pair and metric: the same draws
    for i, a in enumerate(runs):
        for b in runs[i + 1 :]:
            for kpi in kpis:
                va, vb = unit_matrix(units, a, kpi), unit_matrix(units, b, kpi)
                if not va.size or va.shape != vb.shape or np.isnan(va).any() or np.isnan(vb).any():
                    continue
                diff = va - vb
                shape = (diff.shape[0], diff.shape[1])
                if shape not in draws:
                    draws[shape] = draw_indices(*shape, boot)
                low, high = interval(resampled_means(diff, draws[shape]), boot.level)
                per_day = diff.mean(axis=1)
                nonzero = per_day[per_day != 0]
                p = float(wilcoxon(nonzero).pvalue) if len(nonzero) else 1.0
                rows.append(
                    {
                        "a": a,
                        "b": b,
                        "kpi": kpi,
                        "mean_diff": float(diff.mean()),
                        "ci_low": low,
                        "ci_high": high,
                        "wilcoxon_p": p,
                        "days_a_above": int((per_day > 0).sum()),
                        "days_a_below": int((per_day < 0).sum()),
                        "days_tied": int((per_day == 0).sum()),
                    }
                )
    return pd.DataFrame(
        rows,
        columns=[
            "a", "b", "kpi", "mean_diff", "ci_low", "ci_high", "wilcoxon_p",
            "days_a_above", "days_a_below", "days_tied",
        ],
    )  # fmt: skip
