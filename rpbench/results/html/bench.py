"""``report.html`` of a solver benchmark (``rpbench bench --html``): the per-preset summary in the field's
terms (:mod:`rpbench.results.benchmarks`), the performance profile, times against model size, the full table."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench.results.benchmarks import SHIFT_S, performance_profile, preset_summary
from rpbench.results.html import figures
from rpbench.results.html.page import Cell, Page


def bench_page(table: pd.DataFrame, title: str, command: str | None = None) -> Page:
    page = Page(f"rpbench bench: {title}")
    page.heading(f"rpbench bench: {title}", 1)
    page.paragraph(
        f"{table['model'].nunique()} models, {table['preset'].nunique()} presets. A model counts as solved by a "
        "preset when it is proven optimal and agrees with the other presets' optimum."
    )
    if command:
        page.code(command)
    page.heading("Per preset", 2)
    summary = preset_summary(table)
    head = ["preset", "models", "solved", "SGM, all models (ms)", "SGM, models all solved (ms)", "fastest on"]
    page.table(
        head,
        (
            [str(p)]
            + [
                Cell(f"{int(r.models)}", numeric=True),
                Cell(f"{int(r.solved)}", numeric=True),
                Cell(_ms(r.sgm_all_ms), {"value": repr(float(r.sgm_all_ms))}, numeric=True),
                Cell(f"{r.sgm_common_ms:.3f}", {"value": repr(float(r.sgm_common_ms))}, numeric=True),
                Cell(f"{int(r.fastest)}", numeric=True),
            ]
            for p, r in summary.iterrows()
        ),
        ident="bench-summary",
        caption=f"SGM: shifted geometric mean of build + solve + extract time, shift {SHIFT_S * 1e3:g} ms. Over "
        "all models an unsolved one counts at its time limit; where a solve was killed by the hard timeout "
        "no time was recorded, and the mean over all models shows as a dash.",
    )
    page.heading("Performance profile", 2)
    page.figure(
        "fig-profile",
        figures.performance_profile(performance_profile(table)),
        "For each preset, the share of models it solved within τ times the fastest preset's time (Dolan and "
        "Moré); the value at τ = 1 is the share where it was fastest, the right end the share it solved.",
    )
    page.heading("Time against model size", 2)
    page.figure("fig-times", figures.bench_times(table), "Proven-optimal solves only; one symbol per structure.")
    page.heading("Every solve", 2)
    cols = ["model", "preset", "structure", "cols", "status", "objective", "gap", "total_s", "message"]
    cols = [c for c in cols if c in table.columns]
    page.table(
        cols,
        (
            [str(row[cols[0]])] + [Cell(_cell(row[c]), numeric=c != "message") for c in cols[1:]]
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


def write_bench_html(table: pd.DataFrame, path: Path, title: str, command: str | None = None) -> Path:
    path.write_text(bench_page(table, title, command).render(), encoding="utf-8")
    return path


def _ms(value: float) -> str:
    return "–" if value != value else f"{value:.3f}"


def _cell(value) -> str:
    if isinstance(value, float):
        return "" if value != value else f"{value:.6g}"
    return str(value)
