"""Many days of a dated scenario: one comparison per day (in parallel), then per-day and mean KPIs.

A multi-day folder holds one ordinary results folder per date (each
checkable with ``rpbench check``) plus ``by_day.csv`` (date, run, kpi,
value), ``summary.csv`` (mean, std, min, max over days) and a report with a
per-day plot per metric.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from rpbench import files, results
from rpbench.harness import sidecar
from rpbench.harness.comparison import ComparisonTask, run_task
from rpbench.harness.outcome import Outcome
from rpbench.harness.parallel import run_tasks
from rpbench.report.comparison import findings, fmt, markdown_table, offline_notes, table_rows
from rpbench.report.html import write_html
from rpbench.report.plots import MULTIDAY_PLOT_KPIS, per_day_figures
from rpbench.report.tables import csv_table, latex_table
from rpbench.results import layout
from rpbench.results.folder import write_parent_meta
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.parents import bracket_by_day, by_day_table, day_folders
from rpbench.results.ratios import RATIO_KPIS
from rpbench.results.read import load_kpis
from rpbench.results.runs import markdown_cell, run_label, run_styles
from rpbench.results.store import check_new_folder
from rpbench.scenarios import SCENARIOS
from rpbench.spec import DEFAULT_FIGURE_FORMATS, RunSpec


def run_days(
    spec: RunSpec,
    dates: list[str],
    out: str | None = None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | None = None,
) -> Outcome:
    """One comparison per date of ``spec``'s scenario, in parallel, then the per-day and mean tables; returns
    the folder's outcome (its table: each KPI's mean over the days; its children: the days).

    The data folder is resolved once, here (:meth:`~rpbench.scenarios.ScenarioRequest.resolved`): worker
    processes look for none of their own.  ``progress``: a bar over the days (default: when stderr is a
    terminal).
    """
    check_new_folder(out)
    spare = sidecar.may_fork()  # asked now: at the end the load average still holds the days' own load
    request = spec.request.resolved()
    default = f"{results.timestamp()}_{request.name}_{dates[0]}..{dates[-1]}_{spec.preset}"
    with results.new_results_folder(out, default) as (tmp, final):
        tasks = [ComparisonTask(spec.for_request(request.replace(date=d)), str(tmp / d)) for d in dates]
        days = run_tasks(run_task, tasks, workers=workers, scheduler=scheduler, label="days", progress=progress)
        write_parent_meta(
            tmp,
            "multi-day",
            dates,
            {
                "scenario": request.name,
                "dates": dates,
                "strategies": spec.names,
                "preset": spec.preset,
                "sample": request.sample,
                "seed": request.seed,
                "params": request.overrides,
                "command": spec.command,
                **({"decision_budget_s": spec.decision_budget_s} if spec.decision_budget_s is not None else {}),
            },
        )
        stats = write_summary(tmp)
        write_multiday_report(tmp, name=final.name, formats=spec.formats, fork=spare)
        write_html(tmp, name=final.name)
    mean = stats["mean"].unstack("run")[spec.names]
    return Outcome(tmp, mean, children=tuple(days)).moved_to(final)


def write_summary(parent: Path) -> pd.DataFrame:
    """``by_day.csv`` (every day's KPIs) and ``summary.csv`` (mean, std, min, max and count over the days, per
    run and KPI); returns the latter, indexed by (run, kpi)."""
    table = by_day_table(parent)
    table.to_csv(parent / "by_day.csv", index=False)
    stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
    stats.reset_index().to_csv(parent / "summary.csv", index=False)
    return stats


def write_multiday_report(
    parent: Path, name: str | None = None, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS, *, fork: bool = False
) -> Path:
    """``report.md`` of a multi-day folder: mean KPIs, per-day key KPIs, findings per day, plots (in
    ``formats``; with ``fork``, every other one drawn by a forked child meanwhile)."""
    meta = results.read_meta(parent)
    table = by_day_table(parent)
    mean = table.groupby(["kpi", "run"], sort=False)["value"].mean().unstack("run")
    runs = [r for r in meta.get("strategies", []) if r in mean.columns]
    mean = mean[runs]
    days = day_folders(parent)
    first_meta = results.read_meta(days[0])
    first, styles = first_meta["scenario"], run_styles(first_meta)
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
    brackets = bracket_by_day(parent)
    lines += ["## Mean over days", "", markdown_table(mean, styles=styles), ""]
    lines += mean_bracket_lines(brackets) + offline_notes(mean, {})
    caption = (
        f"rpbench, scenario {scenario} (sample {sample}): mean over {len(days)} {what}, "
        f"{meta['dates'][0]} .. {meta['dates'][-1]}"
    )
    files.write_text(
        parent / layout.TABLE_TEX, latex_table(mean, table_rows(mean), fmt, caption=caption, styles=styles)
    )
    csv_table(mean, table_rows(mean), styles).to_csv(parent / layout.TABLE_CSV)
    lines += [f"The mean table is also `{layout.TABLE_TEX}` (LaTeX, booktabs) and `{layout.TABLE_CSV}` (raw values).",
              ""]  # fmt: skip
    lines += bracket_table_lines(brackets, styles)
    key = ["total_saving_km", "avg_detour_m", "response_rate", "pairing_ratio"]
    for kpi in key + [r for r in RATIO_KPIS if r in set(table["kpi"])]:
        wide = table[table["kpi"] == kpi].pivot(index="date", columns="run", values="value")[runs]
        lines += [
            f"### {KPI_LABELS.get(kpi, kpi)} per day",
            "",
            "| date | " + " | ".join(markdown_cell(run_label(r, styles)) for r in runs) + " |",
            "|---|" + "---:|" * len(runs),
        ]
        lines += [f"| {d} | " + " | ".join(fmt(kpi, wide.loc[d, r]) for r in runs) + " |" for d in wide.index]
        lines.append("")
    claims: dict[str, list[bool]] = {}
    for day in days:
        f = findings(load_kpis(day))
        if f:
            for claim, held in f.items():
                claims.setdefault(claim, []).append(held)
    if claims:
        lines += ["## Do the paper's findings hold?", "", "| claim | days where it holds |", "|---|---:|"]
        lines += [f"| {c} | {sum(v)} of {len(v)} |" for c, v in claims.items()]
        lines.append("")
    mine, theirs = sidecar.side_by_side(
        lambda: per_day_figures(table, parent, MULTIDAY_PLOT_KPIS[0::2], styles, formats=formats),
        lambda: per_day_figures(table, parent, MULTIDAY_PLOT_KPIS[1::2], styles, formats=formats),
        fork=fork,
    )
    plots = sorted(mine + theirs, key=lambda path: MULTIDAY_PLOT_KPIS.index(path.stem.removeprefix("by_day_")))
    if plots:
        lines += ["## Per-day plots", ""] + [f"![{p.stem}]({p.name})" for p in plots] + [""]
    lines += [
        "Each day's folder is an ordinary results folder: `rpbench check PATH/<date>`, PATH being the path to "
        f"`{name or parent.name}`, the folder holding this report.",
        "",
    ]
    path = parent / "report.md"
    files.write_text(path, "\n".join(lines))
    return path


def mean_bracket_lines(brackets: pd.DataFrame) -> list[str]:
    """The line under the mean table: the days' mean U, LB and U / LB (the bracket around each day's OPT)."""
    lb = brackets["best_known_saving_km"]
    if lb.isna().all():
        return []
    u, ratio = brackets["upper_bound_km"], brackets["bound_over_best_known"]
    if u.isna().all():
        mean_lb = fmt("total_saving_km", lb.mean())
        return [f"Each day's OPT is at least its LB, the best known schedule's saving: {mean_lb} km on average.", ""]
    return [
        f"Each day's OPT lies in [LB, U]; over the days LB is {fmt('total_saving_km', lb.mean())} km and U "
        f"{fmt('total_saving_km', u.mean())} km on average, U / LB {fmt('bound_over_best_known', ratio.mean())} "
        "(the mean of the days' ratios).",
        "",
    ]


def bracket_table_lines(brackets: pd.DataFrame, styles) -> list[str]:
    """The bracket per day: U, LB, the run that gave LB and U / LB."""
    if brackets["best_known_saving_km"].isna().all():
        return []
    lines = [
        "### Bracket of the optimum per day",
        "",
        "OPT, the largest saving of any schedule of the simulator, lies in [LB, U]: U the proven upper bound, LB "
        "the best known schedule (the largest saving among the day's simulated runs, docs/simulator.md).",
        "",
        "| date | U (km) | LB (km) | best known schedule | U / LB |",
        "|---|---:|---:|---|---:|",
    ]
    for _, b in brackets.iterrows():
        who = markdown_cell(run_label(b["best_known_run"], styles)) if b["best_known_run"] else "/"
        lines.append(
            f"| {b['date']} | {fmt('total_saving_km', b['upper_bound_km'])} | "
            f"{fmt('total_saving_km', b['best_known_saving_km'])} | {who} | "
            f"{fmt('bound_over_best_known', b['bound_over_best_known'])} |"
        )
    return [*lines, ""]
