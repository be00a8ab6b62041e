"""PNG plots for reports (matplotlib, headless), each a pure function of tables read from result files."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pandas as pd

from rpbench.results.metrics import KPI_LABELS
from rpbench.results.runs import run_color, run_label

HOURLY_PANELS = [
    ("avg_shared_m", "(a) Average shared distance (m)"),
    ("avg_detour_m", "(b) Average detour (m)"),
    ("total_saving_km", "(c) Distance saving (km)"),
    ("response_rate", "(d) Response rate"),
]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(plt, fig, path: Path, title: str) -> Path:
    """Title (wrapped: scenario labels are long), lay out, write the PNG, free the figure."""
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _label(run: str) -> tuple[str, str | None]:
    return run_label(run), run_color(run)


def hourly_figure(hourly: pd.DataFrame, path: Path, title: str) -> Path:
    """The paper's 24-hour comparison: four panels, one line per run (``hourly.csv`` layout)."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    for ax, (col, name) in zip(axes.ravel(), HOURLY_PANELS, strict=True):
        for run, g in hourly.groupby("run", sort=False):
            label, color = _label(run)
            ax.plot(g["hour"], g[col], marker="o", ms=3, label=label, color=color)
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("hour of day (request time)")
    axes[0, 0].legend(fontsize=8)
    return _save(plt, fig, path, title)


def per_day_figures(by_day: pd.DataFrame, folder: Path, kpis: list[str]) -> list[Path]:
    """One PNG per KPI: value per day, one line per run (``by_day`` columns date, run, kpi, value)."""
    plt = _pyplot()
    paths = []
    for kpi in kpis:
        sel = by_day[by_day["kpi"] == kpi]
        if sel.empty:
            continue
        fig, ax = plt.subplots(figsize=(9.5, 3.6))
        for run, g in sel.groupby("run", sort=False):
            label, color = _label(run)
            ax.plot(pd.to_datetime(g["date"]), g["value"], marker="o", ms=3, label=label, color=color)
        ax.set_title(KPI_LABELS.get(kpi, kpi), fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))  # beside: lines fill the plot
        fig.autofmt_xdate()
        fig.tight_layout()
        path = folder / f"by_day_{kpi}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def sweep_figure(table: pd.DataFrame, parameter: str, kpis: list[str], path: Path, title: str) -> Path:
    """KPIs against a swept parameter (``table`` columns value, run, kpi, value_kpi)."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(kpis), figsize=(3.6 * len(kpis), 3.4))
    axes = [axes] if len(kpis) == 1 else list(axes)
    for ax, kpi in zip(axes, kpis, strict=True):
        sel = table[table["kpi"] == kpi]
        for run, g in sel.groupby("run", sort=False):
            label, color = _label(run)
            ax.plot(g["point"], g["value"], marker="o", ms=3, label=label, color=color)
        ax.set_xlabel(parameter)
        ax.set_title(KPI_LABELS.get(kpi, kpi), fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    return _save(plt, fig, path, title)


def bench_figure(table: pd.DataFrame, path: Path, title: str) -> Path:
    """Solver time (build + solve + extract) against model size, one panel per structure, one line per preset.

    ``table`` is a :func:`rpbench.bench.runner.run_benchmark` table; rows without a
    proven optimum are left out (their time is a time limit, not a solve).
    """
    plt = _pyplot()
    from matplotlib.ticker import NullFormatter

    done = table[table["status"] == "optimal"]
    structures = list(dict.fromkeys(table["structure"]))
    fig, axes = plt.subplots(1, len(structures), figsize=(4.2 * len(structures), 3.8), squeeze=False)
    for ax, structure in zip(axes[0], structures, strict=True):
        for preset, g in done[done["structure"] == structure].groupby("preset", sort=True):
            g = g.sort_values("cols")
            ax.plot(g["cols"], g["total_s"] * 1e3, marker="o", ms=3, label=preset)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # decade labels only: minor ones overlap
        ax.set_xlabel("model columns")
        ax.set_title(structure, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("solver time, proven optimal (ms)")
    axes[0, 0].legend(fontsize=8)
    return _save(plt, fig, path, title)
