"""The tables of a parent folder (multi-day or sweep), gathered from its children's ``kpis.csv``.

The harness writes them (``by_day.csv``, ``summary.csv``, ``sweep.csv``) and
the checker recomputes them, so they live here, below both.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.results.ratios import BOUND, best_known, over, savings_of
from rpbench.results.read import load_kpis
from rpbench.results.runs import simulated_runs


def day_folders(parent: Path) -> list[Path]:
    """The per-day results folders of a multi-day folder, by date."""
    return sorted(p for p in parent.iterdir() if p.is_dir() and (p / "meta.json").is_file())


def by_day_table(parent: Path) -> pd.DataFrame:
    """Tidy (date, run, kpi, value) over the day folders, each day's ratio and bracket rows included."""
    frames = []
    for day in day_folders(parent):
        wide = load_kpis(day)
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(date=day.name))
    if not frames:
        raise ResultsError(f"{str(parent)!r} holds no per-day results folders")
    return pd.concat(frames, ignore_index=True)[["date", "run", "kpi", "value"]]


def bracket_by_day(parent: Path) -> pd.DataFrame:
    """Per day of a multi-day folder, the bracket around its optimum (:mod:`rpbench.results.ratios`): U (NaN
    without a bound run), LB, the run that gave LB and U / LB."""
    rows = []
    for day in day_folders(parent):
        wide = load_kpis(day)
        lb = best_known(savings_of(wide, simulated_runs(results.read_meta(day), map(str, wide.columns))))
        bound = float(wide.loc["total_saving_km", BOUND]) if BOUND in wide.columns else math.nan
        rows.append(
            {
                "date": day.name,
                "upper_bound_km": bound,
                "best_known_saving_km": lb.saving_km if lb else math.nan,
                "best_known_run": lb.run if lb else "",
                "bound_over_best_known": over(bound, lb.saving_km) if lb else math.nan,
            }
        )
    return pd.DataFrame(rows, columns=["date", "upper_bound_km", "best_known_saving_km", "best_known_run",
                                       "bound_over_best_known"])  # fmt: skip


def sweep_table(parent: Path) -> pd.DataFrame:
    """Tidy (point, label, run, kpi, value) over a sweep folder's points."""
    meta = results.read_meta(parent)
    frames = []
    for p in meta["points"]:
        wide = load_kpis(parent / p["label"])
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(point=p["value"], label=p["label"]))
    return pd.concat(frames, ignore_index=True)[["point", "label", "run", "kpi", "value"]]
