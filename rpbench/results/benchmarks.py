"""The solver-benchmarking field's summaries of a benchmark table (:func:`rpbench.bench.runner.run_benchmark`).

* **Shifted geometric mean** of solve times (Achterberg 2007; Mittelmann's benchmarks): ``exp(mean(log(t +
  s))) - s``, the shift ``s`` damping the weight of the very fast models.  Over all models an unsolved one
  counts at the time it was given up at (its time limit), which only flatters the preset; a solve killed by
  the hard timeout recorded no time, and the mean over all models is then undefined (NaN).  The mean over
  the models every preset solved is always defined.
* **Performance profile** (Dolan and Moré 2002): for each preset p and model m, ``r = t_pm / min_p t_pm``
  over the presets that solved m; ``rho_p(tau)`` is the share of models with ``r <= tau``; an unsolved
  model never counts.  "Solved" is: proven optimal and agreeing with the other presets' optimum.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: The shift of :func:`shifted_geometric_mean`, in seconds: rpbench's models solve in milliseconds, so a
#: 10 ms shift plays the role the field's 10 s shift plays for MIPs that run for minutes.
SHIFT_S = 0.01


def solved(table: pd.DataFrame) -> pd.Series:
    """Rows that count as solved: proven optimal, and not disagreeing with the other presets' optimum."""
    agrees = table["agrees"] if "agrees" in table else pd.Series(True, index=table.index)
    return (table["status"] == "optimal") & (agrees.astype("boolean").fillna(True).astype(bool))


def shifted_geometric_mean(times: np.ndarray, shift: float = SHIFT_S) -> float:
    times = np.asarray(times, dtype=float)
    if not len(times):
        return float("nan")
    return float(np.exp(np.mean(np.log(times + shift))) - shift)


def preset_summary(table: pd.DataFrame, shift: float = SHIFT_S) -> pd.DataFrame:
    """Per preset: models run, solved, the shifted geometric mean of total time over all its models and over
    the models every preset solved, and the number of models where it was fastest."""
    ok = solved(table)
    everyone = table[ok].groupby("model")["preset"].nunique() == table["preset"].nunique()
    common = set(everyone[everyone].index)
    ratios = performance_ratios(table)
    rows = []
    for preset, g in table.groupby("preset", sort=True):
        mine = ok[g.index]
        rows.append(
            {
                "preset": preset,
                "models": len(g),
                "solved": int(mine.sum()),
                "sgm_all_ms": 1e3 * shifted_geometric_mean(g["total_s"].to_numpy(), shift),
                "sgm_common_ms": 1e3 * shifted_geometric_mean(g[g["model"].isin(common)]["total_s"].to_numpy(), shift),
                "fastest": int((ratios[preset] == 1.0).sum()) if preset in ratios else 0,
            }
        )
    return pd.DataFrame(rows).set_index("preset")


def performance_ratios(table: pd.DataFrame) -> pd.DataFrame:
    """Model x preset: time over the fastest solving preset's time (inf: not solved by that preset)."""
    ok = table[solved(table)]
    times = ok.pivot_table(index="model", columns="preset", values="total_s", aggfunc="min")
    times = times.reindex(index=sorted(set(table["model"])), columns=sorted(set(table["preset"])))
    best = times.min(axis=1)
    return (times.div(best, axis=0)).fillna(np.inf)


def performance_profile(table: pd.DataFrame) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per preset, the steps of rho(tau): the sorted finite ratios and the share of models at or below each."""
    ratios = performance_ratios(table)
    n = len(ratios)
    out = {}
    for preset in ratios.columns:
        r = np.sort(ratios[preset].to_numpy())
        r = r[np.isfinite(r)]
        out[str(preset)] = (r, np.arange(1, len(r) + 1) / n if n else r)
    return out
