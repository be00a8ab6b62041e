"""Peak hours of many days: one comparison per day (in parallel), then per-day and mean KPIs.

A multi-day folder holds one ordinary results folder per date (each
checkable with ``rpbench check``) plus ``by_day.csv`` (date, run, kpi,
value), ``summary.csv`` (mean, std, min, max over days) and a report with a
per-day plot per metric.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from . import results
from .data import available_peak_dates
from .data.orders import parse_date
from .exceptions import ParameterError
from .metrics import KPI_ORDER
from .parallel import run_tasks
from .paths import require_data_dir


def parse_dates(text: str, data_dir: Path) -> list[str]:
    """``A..B`` (inclusive; the days in range that have an order file) or ``A,B,C`` (each must exist)."""
    have = available_peak_dates(data_dir)
    if ".." in text:
        first, _, last = text.partition("..")
        a, b = parse_date(first.strip()), parse_date(last.strip())
        if b < a:
            raise ParameterError(f"--dates {text!r}: the range ends before it starts")
        dates = [d for d in have if a <= dt.date.fromisoformat(d) <= b]
        if not dates:
            raise ParameterError(f"--dates {text!r}: no peak-hour order file in that range "
                                 f"(available: {', '.join(have) or 'none'})")
        return dates
    dates = [parse_date(d.strip()).isoformat() for d in text.split(",") if d.strip()]
    missing = [d for d in dates if d not in have]
    if missing or not dates:
        raise ParameterError(f"--dates {text!r}: no peak-hour order file for {', '.join(missing) or '(none)'} "
                             f"(available: {', '.join(have) or 'none'})")
    return dates


@dataclass(frozen=True)
class DayTask:
    """Everything a worker process needs to run one day (picklable)."""

    date: str
    out: str
    data_dir: str
    sample: float | None
    seed: int
    param_overrides: dict
    fleet_placement: str
    strategies: tuple
    preset: str
    strategy_options: dict
    command: str | None
    oracle_solver: str | None = None


def run_day(task: DayTask) -> str:
    """Worker entry point: one day's comparison written to ``task.out``."""
    from .harness import run_comparison
    from .scenarios import build_scenario
    scenario = build_scenario("haikou-peak", data_dir=task.data_dir, date=task.date, sample=task.sample,
                              seed=task.seed, param_overrides=task.param_overrides,
                              fleet_placement=task.fleet_placement)
    folder, _ = run_comparison(scenario, list(task.strategies), task.preset, out=task.out,
                               strategy_options=task.strategy_options, progress=False,
                               scenario_args={"date": task.date, "sample": task.sample, "seed": task.seed,
                                              "params": task.param_overrides,
                                              "fleet_placement": task.fleet_placement},
                               command=task.command, oracle_solver=task.oracle_solver)
    return str(folder)


def run_days(dates: list[str], *, data_dir: str | None, sample: float | None, seed: int,
             param_overrides: dict[str, Any], fleet_placement: str, strategies: list[str], preset: str,
             strategy_options: dict, out: str | None, workers: int | None, scheduler: str | None,
             command: str | None, oracle_solver: str | None = None) -> Path:
    folder_data = str(require_data_dir(data_dir, what="multi-day runs"))
    default = f"{results.timestamp()}_haikou-peak_{dates[0]}..{dates[-1]}_{preset}"
    with results.new_results_folder(out, default) as (tmp, final):
        tasks = [DayTask(date=d, out=str(tmp / d), data_dir=folder_data, sample=sample, seed=seed,
                         param_overrides=param_overrides, fleet_placement=fleet_placement,
                         strategies=tuple(strategies), preset=preset, strategy_options=strategy_options,
                         command=command, oracle_solver=oracle_solver) for d in dates]
        run_tasks(run_day, tasks, workers=workers, scheduler=scheduler, label="days")
        results.write_json(tmp / "meta.json", {"rpbench_results": 1, "kind": "multi-day", "dates": dates,
                                               "strategies": strategies, "preset": preset, "sample": sample,
                                               "seed": seed, "params": param_overrides, "command": command,
                                               **results.environment()})
        summarize(tmp)
        from .report import write_multiday_report
        write_multiday_report(tmp, name=final.name)
    return final


def day_folders(parent: Path) -> list[Path]:
    return sorted(p for p in parent.iterdir() if p.is_dir() and (p / "meta.json").is_file())


def by_day_table(parent: Path) -> pd.DataFrame:
    """Tidy (date, run, kpi, value) over the day folders, with the competitive ratio when Oracle-1 ran."""
    from .report import load_kpis
    frames = []
    for day in day_folders(parent):
        wide = load_kpis(day)
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(date=day.name))
    if not frames:
        from .exceptions import ResultsError
        raise ResultsError(f"{str(parent)!r} holds no per-day results folders")
    return pd.concat(frames, ignore_index=True)[["date", "run", "kpi", "value"]]


def summarize(parent: Path) -> pd.DataFrame:
    table = by_day_table(parent)
    table.to_csv(parent / "by_day.csv", index=False)
    stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
    stats.reset_index().to_csv(parent / "summary.csv", index=False)
    return stats


MULTIDAY_PLOT_KPIS = [k for k in KPI_ORDER if k != "platform_profit_cny"] + ["competitive_ratio",
                                                                             "competitive_ratio_enroute"]
