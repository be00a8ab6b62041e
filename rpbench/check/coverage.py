"""``leaderboard-runs``: no run the units hold is left out of what an evaluation shows.

A run is held by the units when every unit reports a value of a leaderboard metric for it (the condition
under which the leaderboard ranks it).  Then leaderboard.csv has its row for that metric, the paired tests
pair it with every other simulated run holding that metric, the leaderboard of report.md and of table.tex
show it with a number, and the page's leaderboard figure draws it.  This reads the units' KPI tables and
the files alone, not the code that wrote the tables: a run stored under another name than the protocol's
(a ``module:Class`` plug-in runs under its class's name) cannot drop out of the ranking unnoticed.  A row is
found by its run's label, with or without the clairvoyant mark (whether the label is right is ``report``'s
check, not this one's).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import combinations
from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.check.core import RunCheck
from rpbench.check.rendered import latex_rows, markdown_tables, page_figure
from rpbench.exceptions import ResultsError
from rpbench.report.html.figures import plotly_text
from rpbench.report.tables import latex_escape
from rpbench.results.layout import LEADERBOARD, PAIRED, REPORT, REPORT_HTML, TABLE_TEX
from rpbench.results.ratios import RATIO_KPIS
from rpbench.results.runs import CLAIRVOYANT_MARK, markdown_cell, run_label

COVERAGE_CHECK = "leaderboard-runs"
#: What a leaderboard row shows for a metric it has no value of.
NO_VALUE = "/"


def held_metrics(units: pd.DataFrame, metrics: Sequence[str]) -> dict[str, list[str]]:
    """Each run's metrics of ``metrics`` that every unit reports a value of (``units``: day, seed, run, kpi,
    value over all units)."""
    n_units = units[["day", "seed"]].drop_duplicates().shape[0]
    sel = units[units["kpi"].isin(list(metrics)) & units["value"].notna()]
    counts = sel.groupby(["run", "kpi"]).size()
    held: dict[str, list[str]] = {}
    for (run, kpi), n in counts.items():
        if n == n_units:
            held.setdefault(str(run), []).append(str(kpi))
    return {run: [m for m in metrics if m in kpis] for run, kpis in held.items()}


def check_coverage(
    fc: RunCheck,
    parent: Path,
    units: pd.DataFrame,
    board_metrics: Sequence[str],
    paired_metrics: Sequence[str],
    offline: set[str],
    styles: Mapping,
) -> None:
    """Every run the units hold is in leaderboard.csv, the paired tests, report.md, table.tex and the page."""
    held = held_metrics(units, board_metrics)
    _in_leaderboard(fc, parent / LEADERBOARD, held)
    _in_paired(fc, parent / PAIRED, held, set(paired_metrics), offline)
    shown = {run: [m for m in kpis if run not in offline or m not in RATIO_KPIS] for run, kpis in held.items()}
    shown = {run: kpis for run, kpis in shown.items() if kpis}
    labels = {run: run_label(run, styles) for run in shown}
    if (parent / REPORT).is_file():
        tables = [
            t
            for t in markdown_tables((parent / REPORT).read_text(errors="replace"))
            if t and t[0][:2] == ["Rank", "Strategy"]
        ]
        rows = tables[0][1:] if tables else []
        _in_rows(fc, REPORT, rows, {run: markdown_cell(label) for run, label in labels.items()})
    if (parent / TABLE_TEX).is_file():
        rows = latex_rows((parent / TABLE_TEX).read_text(errors="replace"))[1:]
        _in_rows(fc, TABLE_TEX, rows, {run: latex_escape(label) for run, label in labels.items()})
    if (parent / REPORT_HTML).is_file():
        figure = page_figure((parent / REPORT_HTML).read_text(errors="replace"), "fig-leaderboard") or {}
        drawn = {
            str(x).removesuffix(CLAIRVOYANT_MARK) for trace in figure.get("data") or [] for x in trace.get("x") or []
        }
        for run, label in labels.items():
            if plotly_text(label).removesuffix(CLAIRVOYANT_MARK) not in drawn:
                fc.fail(
                    COVERAGE_CHECK, f"{REPORT_HTML}'s leaderboard figure leaves out run {run!r}, which the units hold"
                )
    fc.checked["held_runs"] = len(held)


def _in_leaderboard(fc: RunCheck, path: Path, held: dict[str, list[str]]) -> None:
    try:
        board = results.read_csv(path)
    except ResultsError:
        return  # parent-tables says why
    rows = set(
        zip(
            board.get("run", pd.Series(dtype=str)).astype(str),
            board.get("kpi", pd.Series(dtype=str)).astype(str),
            strict=True,
        )
    )
    for run, kpis in held.items():
        lost = [k for k in kpis if (run, k) not in rows]
        if lost:
            fc.fail(COVERAGE_CHECK, f"{path.name} leaves out run {run!r} ({', '.join(lost)}), which every unit holds")


def _in_paired(fc: RunCheck, path: Path, held: dict[str, list[str]], metrics: set[str], offline: set[str]) -> None:
    try:
        pairs = results.read_csv(path)
    except ResultsError:
        return
    cols = [pairs.get(c, pd.Series(dtype=str)).astype(str) for c in ("a", "b", "kpi")]
    rows = {(a, b, k) for a, b, k in zip(*cols, strict=True)} | {(b, a, k) for a, b, k in zip(*cols, strict=True)}
    simulated = sorted(r for r in held if r not in offline)
    for a, b in combinations(simulated, 2):
        lost = [k for k in sorted(metrics & set(held[a]) & set(held[b])) if (a, b, k) not in rows]
        if lost:
            fc.fail(COVERAGE_CHECK, f"{path.name} has no test of {a!r} against {b!r} ({', '.join(lost)})")


def _in_rows(fc: RunCheck, name: str, rows: list[list[str]], labels: dict[str, str]) -> None:
    """Each run's row (by its label in the second column) shows a number in some metric's cell."""
    shown: dict[str, list[str]] = {}
    for row in rows:
        if len(row) > 2:
            shown.setdefault(row[1], row[2:])
            shown.setdefault(row[1].removesuffix(CLAIRVOYANT_MARK), row[2:])
    for run, label in labels.items():
        cells = shown.get(label, shown.get(label.removesuffix(CLAIRVOYANT_MARK)))
        if cells is None or all(c == NO_VALUE for c in cells):
            fc.fail(COVERAGE_CHECK, f"{name}'s leaderboard shows no value of run {run!r}, which the units hold")
