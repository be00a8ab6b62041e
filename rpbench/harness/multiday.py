"""Many days of a dated scenario: one comparison per day (in parallel), then per-day and mean KPIs.

A multi-day folder holds one ordinary results folder per date (each
checkable with ``rpbench check``) plus ``by_day.csv`` (date, run, kpi,
value), ``summary.csv`` (mean, std, min, max over days) and a report with a
per-day plot per metric.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.harness.comparison import run_comparison
from rpbench.harness.parallel import run_tasks
from rpbench.paths import require_data_dir
from rpbench.results.metrics import KPI_LABELS, KPI_ORDER
from rpbench.results.parents import by_day_table, day_folders
from rpbench.results.plots import per_day_figures
from rpbench.results.report import RATIO_ROWS, findings, fmt, load_kpis, markdown_table, offline_notes
from rpbench.results.runs import run_label
from rpbench.scenarios import SCENARIOS, ScenarioRequest
from rpbench.strategies.options import RunOptions


@dataclass(frozen=True)
class DayTask:
    """Everything a worker process needs to run one day (picklable)."""

    request: ScenarioRequest
    out: str
    strategies: tuple
    preset: str
    run_options: dict
    command: str | None
    oracle_solver: str | None = None


def run_day(task: DayTask) -> str:
    """Worker entry point: one day's comparison written to ``task.out``."""
    folder, _ = run_comparison(
        task.request.build(),
        list(task.strategies),
        task.preset,
        out=task.out,
        run_options=task.run_options,
        progress=False,
        request=task.request,
        command=task.command,
        oracle_solver=task.oracle_solver,
    )
    return str(folder)


def run_days(
    request: ScenarioRequest,
    dates: list[str],
    *,
    strategies: list[str],
    preset: str,
    run_options: dict[str, RunOptions],
    out: str | None,
    workers: int | None,
    scheduler: str | None,
    command: str | None,
    oracle_solver: str | None = None,
) -> Path:
    """One comparison per date of ``request``'s scenario, in parallel, then the per-day and mean tables."""
    request = request.replace(data_dir=str(require_data_dir(request.data_dir, what="multi-day runs")))
    default = f"{results.timestamp()}_{request.name}_{dates[0]}..{dates[-1]}_{preset}"
    with results.new_results_folder(out, default) as (tmp, final):
        tasks = [
            DayTask(
                request=request.replace(date=d),
                out=str(tmp / d),
                strategies=tuple(strategies),
                preset=preset,
                run_options=run_options,
                command=command,
                oracle_solver=oracle_solver,
            )
            for d in dates
        ]
        run_tasks(run_day, tasks, workers=workers, scheduler=scheduler, label="days")
        results.write_json(
            tmp / "meta.json",
            {
                "rpbench_results": 1,
                "kind": "multi-day",
                "scenario": request.name,
                "dates": dates,
                "children": list(dates),  # `rpbench check`'s manifest
                "strategies": strategies,
                "preset": preset,
                "sample": request.sample,
                "seed": request.seed,
                "params": request.overrides,
                "command": command,
                **results.environment(),
            },
        )
        summarize(tmp)
        write_multiday_report(tmp, name=final.name)
    return final


def summarize(parent: Path) -> pd.DataFrame:
    table = by_day_table(parent)
    table.to_csv(parent / "by_day.csv", index=False)
    stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
    stats.reset_index().to_csv(parent / "summary.csv", index=False)
    return stats


MULTIDAY_PLOT_KPIS = [k for k in KPI_ORDER if k != "platform_profit_cny"] + [
    "competitive_ratio_bound",
    "competitive_ratio",
]


def write_multiday_report(parent: Path, name: str | None = None) -> Path:
    """``report.md`` of a multi-day folder: mean KPIs, per-day key KPIs, findings per day, plots."""
    meta = results.read_meta(parent)
    table = by_day_table(parent)
    mean = table.groupby(["kpi", "run"], sort=False)["value"].mean().unstack("run")
    runs = [r for r in meta.get("strategies", []) if r in mean.columns]
    mean = mean[runs]
    days = day_folders(parent)
    first = results.read_meta(days[0])["scenario"]
    scenario = meta.get("scenario", "haikou-peak")  # folders written before --dates took any scenario
    what = "peak hours" if scenario == "haikou-peak" else "days"
    sample = first["args"].get("sample") or (SCENARIOS[scenario].default_sample if scenario in SCENARIOS else None)
    lines = [
        f"# rpbench multi-day results: {len(days)} {what}, {meta['dates'][0]} .. {meta['dates'][-1]}",
        "",
        f"- scenario `{scenario}`, sample {sample}, seed {meta.get('seed')}, solver preset `{meta.get('preset')}`",
        f"- rpbench {meta['versions']['rpbench']}, commit `{meta.get('git_commit')}`",
        "",
    ]
    if meta.get("command"):
        lines += ["Command:", "", f"    {meta['command']}", ""]
    lines += ["## Mean over days", "", markdown_table(mean), ""] + offline_notes(mean, {})
    key = ["total_saving_km", "avg_detour_m", "response_rate", "pairing_ratio"]
    for kpi in key + [r for r in RATIO_ROWS if r in set(table["kpi"])]:
        wide = table[table["kpi"] == kpi].pivot(index="date", columns="run", values="value")[runs]
        lines += [
            f"### {KPI_LABELS.get(kpi, kpi)} per day",
            "",
            "| date | " + " | ".join(run_label(r) for r in runs) + " |",
            "|---|" + "---:|" * len(runs),
        ]
        lines += [f"| {d} | " + " | ".join(fmt(kpi, wide.loc[d, r]) for r in runs) + " |" for d in wide.index]
        lines.append("")
    claims = {}
    for day in days:
        f = findings(load_kpis(day))
        if f:
            for claim, held in f.items():
                claims.setdefault(claim, []).append(held)
    if claims:
        lines += ["## Do the paper's findings hold?", "", "| claim | days where it holds |", "|---|---:|"]
        lines += [f"| {c} | {sum(v)} of {len(v)} |" for c, v in claims.items()]
        lines.append("")
    plots = per_day_figures(table, parent, MULTIDAY_PLOT_KPIS)
    if plots:
        lines += ["## Per-day plots", ""] + [f"![{p.stem}]({p.name})" for p in plots] + [""]
    lines += [f"Each day's folder is an ordinary results folder: `rpbench check {name or parent.name}/<date>`.", ""]
    path = parent / "report.md"
    path.write_text("\n".join(lines))
    return path
