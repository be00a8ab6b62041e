"""The tables of a parent folder (multi-day or sweep), gathered from its children's ``kpis.csv``.

The harness writes them (``by_day.csv``, ``summary.csv``, ``sweep.csv``) and
the checker recomputes them, so they live here, below both.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.results.metrics import KPI_ORDER
from rpbench.results.report import load_kpis

#: The KPIs of a multi-day report's per-day plots (PNG and report.html).
MULTIDAY_PLOT_KPIS = [k for k in KPI_ORDER if k != "platform_profit_cny"] + [
    "competitive_ratio_bound",
    "competitive_ratio",
]


def day_folders(parent: Path) -> list[Path]:
    """The per-day results folders of a multi-day folder, by date."""
    return sorted(p for p in parent.iterdir() if p.is_dir() and (p / "meta.json").is_file())


def by_day_table(parent: Path) -> pd.DataFrame:
    """Tidy (date, run, kpi, value) over the day folders, with the ratio rows of the offline runs present."""
    frames = []
    for day in day_folders(parent):
        wide = load_kpis(day)
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(date=day.name))
    if not frames:
        raise ResultsError(f"{str(parent)!r} holds no per-day results folders")
    return pd.concat(frames, ignore_index=True)[["date", "run", "kpi", "value"]]


def sweep_table(parent: Path) -> pd.DataFrame:
    """Tidy (point, label, run, kpi, value) over a sweep folder's points."""
    meta = results.read_meta(parent)
    frames = []
    for p in meta["points"]:
        wide = load_kpis(parent / p["label"])
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(point=p["value"], label=p["label"]))
    return pd.concat(frames, ignore_index=True)[["point", "label", "run", "kpi", "value"]]
