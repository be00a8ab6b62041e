"""``report.html`` of a solver benchmark (``rpbench bench --html``): the per-(tier, preset) summary in the field's
terms (:mod:`rpbench.report.bench`), the performance profile, times against model size, every solve, and the
machine and library versions when given."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench.report.bench import performance_profile, profile_steps, summarise, with_verdicts
from rpbench.report.html import figures
from rpbench.report.html.page import Cell, Page


def bench_page(
    table: pd.DataFrame,
    title: str,
    command: str | None = None,
    *,
    shift: float | None = None,
    env: Mapping[str, Any] | None = None,
) -> Page:
    table = with_verdicts(table)
    page = Page(f"rpbench bench: {title}")
    page.heading(f"rpbench bench: {title}", 1)
    page.paragraph(
        f"{table['model'].nunique()} models, {table['preset'].nunique()} presets. A model counts as solved by a "
        "preset when its verdict is optimal: proven optimal, and agreeing with the known values and the other "
        "presets' optimum."
    )
    if command:
        page.code(command)
    if env:
        machine, versions = env.get("machine", {}), env.get("versions", {})
        page.paragraph(
            f"Machine: {machine.get('platform')}, {machine.get('cpu_model') or machine.get('processor')}, "
            f"{machine.get('logical_cores', machine.get('cpus'))} logical cores, {machine.get('memory_gib')} GiB. "
            + ", ".join(f"{k} {v}" for k, v in sorted(versions.items()))
            + "."
        )
    page.heading("Per preset", 2)
    summary = summarise(table, shift)
    head = ["tier", "preset", "models", "solved", "SGM (ms)", "SGM / best", "shift (ms)", "repeat spread"]
    page.table(
        head,
        (
            [str(r.tier)]
            + [
                str(r.preset),
                Cell(f"{int(r.instances)}", numeric=True),
                Cell(f"{int(r.solved)}", numeric=True),
                Cell(_ms(1e3 * r.sgm_s), {"value": repr(float(r.sgm_s))}, numeric=True),
                Cell(_ratio(r.sgm_ratio), numeric=True),
                Cell(f"{1e3 * r.shift_s:g}", numeric=True),
                Cell(_pct(r.repeat_spread), numeric=True),
            ]
            for r in summary.itertuples()
        ),
        ident="bench-summary",
        caption="SGM: shifted geometric mean of the fastest run's build + solve + extract time, with the shift "
        "shown; an unsolved model (time limit, wrong answer, error, killed, out of memory) counts at its time "
        "limit, and where no limit is known the mean shows as a dash. SGM / best: over the tier's fastest "
        "preset. Repeat spread: median of (max - min) / median of the repeated solves' times.",
    )
    page.heading("Performance profile", 2)
    page.figure(
        "fig-profile",
        figures.profile_lines(profile_steps(performance_profile(table))),
        "For each preset, the share of models it solved within τ times the fastest preset's time (Dolan and "
        "Moré); the value at τ = 1 is the share where it was fastest, the right end the share it solved.",
    )
    page.heading("Time against model size", 2)
    solves = table[table["verdict"] == "optimal"]
    page.figure("fig-times", figures.bench_times(solves), "Solved models only; one symbol per structure.")
    page.heading("Every solve", 2)
    cols = ["model", "preset", "tier", "structure", "cols", "status", "verdict", "objective", "gap", "total_s"]
    cols += ["total_s_min", "total_s_median", "total_s_max", "message"]
    cols = [c for c in cols if c in table.columns]
    text = {"preset", "tier", "structure", "status", "verdict", "message"}
    page.table(
        cols,
        (
            [str(row[cols[0]])] + [Cell(_cell(row[c]), numeric=c not in text) for c in cols[1:]]
            for _, row in table.iterrows()
        ),
    )
    return page


#: The columns that make a CSV a benchmark table (``rpbench bench --csv``).
BENCH_COLUMNS = {"model", "preset", "structure", "status", "total_s"}


def bench_tables(folder: Path) -> list[Path]:
    """The benchmark tables (``rpbench bench --csv``) in ``folder``."""
    found = []
    for path in sorted(folder.glob("*.csv")):
        with path.open(encoding="utf-8", errors="replace") as f:
            if set(f.readline().strip().split(",")) >= BENCH_COLUMNS:
                found.append(path)
    return found


def write_bench_folder(folder: Path, dest: Path | None = None) -> Path:
    """``report.html`` of a folder of benchmark tables (all of them, one after the other)."""
    tables = [pd.read_csv(p) for p in bench_tables(folder)]
    table = pd.concat(tables, ignore_index=True)
    what = ", ".join(p.name for p in bench_tables(folder))
    return write_bench_html(table, (dest or folder) / "report.html", f"{folder.name} ({what})")


def write_bench_html(
    table: pd.DataFrame,
    path: Path,
    title: str,
    command: str | None = None,
    *,
    shift: float | None = None,
    env: Mapping[str, Any] | None = None,
) -> Path:
    path.write_text(bench_page(table, title, command, shift=shift, env=env).render(), encoding="utf-8")
    return path


def _ms(value: float) -> str:
    return "–" if value != value else f"{value:.3f}"


def _ratio(value: float) -> str:
    return "–" if value != value else f"{value:.2f}"


def _pct(value: float) -> str:
    return "–" if value != value else f"{100 * value:.0f}%"


def _cell(value) -> str:
    if isinstance(value, float):
        return "" if value != value else f"{value:.6g}"
    return str(value)
