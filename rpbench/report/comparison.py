"""Reports rendered from result files alone (tables here; plots in rpbench.report.plots).

The wide KPI x run table is read by :func:`rpbench.results.read.load_kpis`; :func:`text_table` and
:func:`markdown_table` format it in the paper's Table 2 layout (strategies as columns); :func:`write_report`
writes ``report.md`` and its figures (:data:`FIGURES`) into the folder, or into another one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import files, results
from rpbench.data import paper
from rpbench.exceptions import ResultsError
from rpbench.report.plots import FORMATS_NOTE, hourly_figure, kpi_figure, timeline_figure
from rpbench.report.tables import csv_table, latex_table
from rpbench.results import layout
from rpbench.results.legacy import LEGACY_KPIS
from rpbench.results.metrics import (
    DECISION_PARTS,
    EXTRA_KPIS,
    KPI_LABELS,
    KPI_ORDER,
    TIMELINE_STATES,
    count_at,
    mean_count,
    state_spells,
)
from rpbench.results.ratios import DERIVED_KPIS, RATIO_KPIS, bracket_line
from rpbench.results.read import decision_budget_of, load_kpis, unproven_runs
from rpbench.results.runs import CLAIRVOYANT_MARK, Styles, markdown_cell, run_label, run_styles, simulated_runs
from rpbench.spec import DEFAULT_FIGURE_FORMATS

#: One line under every table with an Oracle-1 column: why its ratio can exceed 1.
ORACLE1_NOTE = (
    "Oracle-1 (the paper's) pairs only orders requested within K̄ of each other, while the strategies "
    "also pair en route, so a strategy can save more than Oracle-1: the saving / Oracle-1 row is the paper's "
    "reference, not a competitive ratio; the competitive ratio divides by the proven upper bound and by the "
    "best known schedule."
)
#: Marks the column of a run whose numbers rest on solver answers not proven optimal (see :func:`unproven_runs`).
UNPROVEN_MARK = "*"
#: The figures of a comparison report: headline KPIs per run, the timeline from the event logs, and the
#: per-hour KPIs of folders covering more than two hours.
KPIS_PNG, TIMELINE_PNG, HOURLY_PNG = layout.KPIS_PNG, layout.TIMELINE_PNG, layout.HOURLY_PNG
FIGURES = (KPIS_PNG, TIMELINE_PNG, HOURLY_PNG)
#: The figure section of a published evaluation unit (:func:`write_report` with ``figures=False``).
UNIT_FIGURES = [
    "## Figures",
    "",
    "This run is one unit of a published evaluation: its figures and page are left out of the copy (the "
    "evaluation's own are in the folder above); rerun the command above to draw them.",
    "",
]
#: A scenario longer than this is drawn in hours (the timeline's axis), not minutes.
LONG_SCENARIO_S = 2 * 3600.0
#: Timeline bin widths (s), the narrowest giving at most :data:`TIMELINE_MAX_BINS` bins over the period.
TIMELINE_BINS_S = (60.0, 120.0, 300.0, 600.0, 900.0, 1800.0, 3600.0)
TIMELINE_MAX_BINS = 240
#: One-off preparations shorter than this are not listed (they are loading, not work worth a line).
PREPARE_SHOWN_S = 0.05
_DECIMALS = {
    "response_rate": 2,
    "pairing_ratio": 2,
    "competitive_ratio_bound": 3,
    "competitive_ratio_best_known": 3,
    "saving_over_oracle1": 3,
    "bound_over_best_known": 2,
    "pairing_ratio_of_orders": 2,
    "matching_pairing_ratio": 2,
}


def fmt(kpi: str, value) -> str:
    """Format a KPI value the way the paper prints it ("/" for undefined)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "/"
    value = float(value) + 0.0
    if kpi in _DECIMALS:
        text = f"{value:.{_DECIMALS[kpi]}f}"
        return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.000"
    if abs(value) >= 100 or kpi.endswith("_s") or kpi.endswith("_m"):
        text = f"{value:,.0f}"
    else:
        text = f"{value:.1f}"
    return text[1:] if text.startswith("-") and float(text.replace(",", "")) == 0 else text


def table_rows(table: pd.DataFrame) -> list[str]:
    """The rows of a comparison table: the paper's KPIs, then the ratios (:data:`~.ratios.RATIO_KPIS`)."""
    return [k for k in KPI_ORDER if k in table.index] + [k for k in RATIO_KPIS if k in table.index]


#: The best-known ratio's row label when no clairvoyant run is compared: LB is then the best of the runs
#: shown, so that run's 1.000 says it was best here, not that it is optimal.
BEST_RUN_HERE_LABEL = "Ratio to the best run here (saving / best saving of these runs)"


def kpi_labels(runs: list[str], styles: Styles | None = None) -> dict[str, str]:
    """The row labels of a comparison of ``runs``: :data:`KPI_LABELS`, the best-known ratio relabelled
    (:data:`BEST_RUN_HERE_LABEL`) when none of the runs is clairvoyant."""
    if any(run_label(r, styles).endswith(CLAIRVOYANT_MARK) for r in runs):
        return KPI_LABELS
    return {**KPI_LABELS, "competitive_ratio_best_known": BEST_RUN_HERE_LABEL}


def text_table(
    table: pd.DataFrame,
    *,
    title: str | None = None,
    unproven: dict[str, str] | None = None,
    styles: Styles | None = None,
) -> str:
    """A plain-text table for the terminal (KPIs as rows, runs as columns); the columns of ``unproven``
    runs (:func:`unproven_runs`) are marked, with a footnote line."""
    rows = table_rows(table)
    cols = list(table.columns)
    unproven = unproven or {}
    head = ["Metric"] + [run_label(c, styles) + (UNPROVEN_MARK if c in unproven else "") for c in cols]
    labels = kpi_labels([str(c) for c in cols], styles)
    body = [[labels.get(k, k)] + [fmt(k, table.loc[k, c]) for c in cols] for k in rows]
    widths = [max(len(r[i]) for r in [head] + body) for i in range(len(head))]
    lines = []
    if title:
        lines.append(title)
    lines.append("  ".join(h.ljust(widths[0]) if i == 0 else h.rjust(widths[i]) for i, h in enumerate(head)))
    lines.append("  ".join("-" * w for w in widths))
    for r in body:
        lines.append("  ".join(x.ljust(widths[0]) if i == 0 else x.rjust(widths[i]) for i, x in enumerate(r)))
    if any(c in unproven for c in cols):
        lines.append(
            f"{UNPROVEN_MARK} not proven optimal: the solver stopped early (time limit or gap), so these "
            "numbers are not those of the run as defined (details on stderr and in report.md)"
        )
    return "\n".join(lines)


def markdown_table(
    table: pd.DataFrame,
    paper_values: dict | None = None,
    unproven: dict[str, str] | None = None,
    styles: Styles | None = None,
) -> str:
    """The Table 2 layout in markdown; with ``paper_values`` each cell reads "rpbench (paper)"; the columns
    of ``unproven`` runs are marked (the footnote is :func:`unproven_notes`)."""
    rows = table_rows(table)
    cols = list(table.columns)
    unproven = unproven or {}
    labels = kpi_labels([str(c) for c in cols], styles)
    out = [
        "| Metric | "
        + " | ".join(
            markdown_cell(run_label(c, styles)) + ("\\" + UNPROVEN_MARK if c in unproven else "") for c in cols
        )
        + " |",
        "|---|" + "---:|" * len(cols),
    ]
    for k in rows:
        cells = []
        for c in cols:
            cell = fmt(k, table.loc[k, c])
            if paper_values is not None:
                ref = (
                    paper_values.get(c, {}).get(k, float("nan"))
                    if k not in RATIO_KPIS
                    else (paper.FL_SAVING_OVER_ORACLE1 if c == "fl" and k == "saving_over_oracle1" else float("nan"))
                )
                cell += f" ({fmt(k, ref)})"
            cells.append(cell)
        out.append(f"| {labels.get(k, k)} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def solver_summary(folder: Path) -> pd.DataFrame | None:
    """Per run: rounds solved, model size, solve and decision time percentiles (a round's decision: the
    strategy's build plus the solver's build, solve and decoding), rounds slower than Δt (and than the
    decision budget, when the folder records one), statuses."""
    path = folder / "rounds.csv.gz"
    if not path.is_file():
        return None
    rounds = pd.read_csv(path)
    if rounds.empty:
        return None
    meta = results.read_meta(folder)
    dt = float(meta.get("params", {}).get("dt_s", float("nan")))
    budget = decision_budget_of(meta)
    rounds = rounds.assign(decision_s=rounds[list(DECISION_PARTS)].sum(axis=1))
    g = rounds.groupby("run", sort=False)
    over_budget = (
        {f"rounds > budget ({budget:g} s)": g["decision_s"].apply(lambda s: int((s > budget).sum()))}
        if budget is not None
        else {}
    )
    return pd.DataFrame(
        {
            "rounds": g.size(),
            "mean cols": g["cols"].mean().round(1),
            "max cols": g["cols"].max(),
            "strategy build p50 (ms)": (g["strategy_build_s"].median() * 1e3).round(3),
            "solve p50 (ms)": (g["solve_s"].median() * 1e3).round(3),
            "solve p95 (ms)": (g["solve_s"].quantile(0.95) * 1e3).round(3),
            "solver total (s)": (g["solver_build_s"].sum() + g["solve_s"].sum() + g["extract_s"].sum()).round(3),
            "decision p50 (ms)": (g["decision_s"].median() * 1e3).round(3),
            "decision p95 (ms)": (g["decision_s"].quantile(0.95) * 1e3).round(3),
            "decision max (ms)": (g["decision_s"].max() * 1e3).round(3),
            f"rounds > Δt ({dt:g} s)": g["decision_s"].apply(lambda s: int((s > dt).sum())),
            **over_budget,
            "not optimal": g["status"].apply(lambda s: int((s != "optimal").sum())),
            "tie moves": g["tie_moves"].sum(),
        }
    )


def unproven_notes(unproven: dict[str, str], styles: Styles | None = None) -> list[str]:
    """The footnote of a report table with marked columns (nothing when every run is proven)."""
    if not unproven:
        return []
    why = "; ".join(f"{run_label(r, styles)}: {text}" for r, text in unproven.items())
    return [
        f"\\{UNPROVEN_MARK} **Not proven optimal.** {why}. The solver stopped before proving optimality "
        "(its preset's time limit or gap), so these columns are not the runs as defined; raise "
        "`time_limit_s`, or rerun with `--strict` to make such runs fail.",
        "",
    ]


#: What a comparison folder's meta.json must hold to be reported (checked once, where a report reads it).
REPORT_META: files.Schema = {
    "scenario": {
        "name": str,
        "label": str,
        "seed": int,
        "summary": {"orders": int, "vehicles": int, "nodes": int},
    },
    "preset": {"name": str, "backend": str},
    "versions": {"rpbench": str},
    "runs": dict,
}


def report_meta(folder: Path) -> dict[str, Any]:
    """A comparison folder's meta.json, refused in one line when it lacks what a report shows."""
    meta = results.read_meta(folder)
    files.check_schema(meta, REPORT_META, repr(str(folder / "meta.json")), ResultsError)
    return meta


def report_markdown(folder: Path, name: str | None = None, figures: list[str] | None = None) -> str:
    """``report.md`` of a comparison folder (``name``: the folder's name in the text; ``figures``: the
    figure section's lines, :func:`figure_lines`, placed after the comparison tables)."""
    meta = report_meta(folder)
    table = load_kpis(folder)
    unproven = unproven_runs(folder)
    sc = meta["scenario"]
    args = sc.get("args", {})
    lines = [f"# rpbench results: {sc['label']}", ""]
    lines += synthetic_lines(sc)
    lines += [
        f"- scenario `{sc['name']}`, seed {sc['seed']}, {sc['summary']['orders']} orders, "
        f"{sc['summary']['vehicles']} vehicles, {sc['summary']['nodes']} nodes",
        f"- solver preset `{meta['preset']['name']}` (backend `{meta['preset']['backend']}`)",
        f"- rpbench {meta['versions']['rpbench']}, commit `{meta.get('git_commit')}`, written {meta.get('created')}",
        "",
    ]
    if meta.get("command"):
        lines += ["Command:", "", f"    {meta['command']}", ""]
    styles = run_styles(meta)
    lines += ["## Comparison (paper Table 2 layout)", "", markdown_table(table, unproven=unproven, styles=styles), ""]
    lines += bracket_lines(table, meta, styles)
    lines += unproven_notes(unproven, styles) + offline_notes(table, meta)
    if paper.table2_applies(sc["name"], args.get("date"), args.get("sample")):
        lines += [
            "## Beside the paper",
            "",
            "Each cell: rpbench (paper Table 2). The paper's numbers are shown for comparison only; "
            "nothing is tuned to them.",
            "",
            markdown_table(table, paper.TABLE2, unproven, styles),
            "",
        ]
    lines += figures or []
    summary = solver_summary(folder)
    if summary is not None:
        lines += [
            "## Solver statistics per run",
            "",
            summary.rename(index=markdown_cell).to_markdown()
            if _has_tabulate()
            else "```\n" + summary.to_string() + "\n```",
            "",
        ]
        lines += budget_lines(meta)
    lines += wall_lines(meta, styles)
    if results.run_names(folder):
        verify = (
            f"Verify this folder with `rpbench check PATH`, PATH being the path to `{name or folder.name}`, "
            "the folder holding this report."
        )
    else:
        verify = (
            "This is a published light copy without the event logs: `check.txt` holds the checker's verdict "
            "on the full folder; rerun the command above to regenerate and re-check it."
        )
    lines += [f"KPI definitions: see `rpbench/results/metrics.py` (and the README). {verify}", ""]
    return "\n".join(lines)


def bracket_lines(table: pd.DataFrame, meta: dict[str, Any], styles: Styles | None = None) -> list[str]:
    """The line under a folder's comparison table saying where OPT lies (:func:`~.ratios.bracket_line`)."""
    line = bracket_line(table, simulated_runs(meta, map(str, table.columns)), fmt, styles)
    return [line, ""] if line else []


def budget_lines(meta: dict[str, Any]) -> list[str]:
    """The sentence under the solver table of a folder run with a decision budget (nothing without one)."""
    budget = decision_budget_of(meta)
    if budget is None:
        return []
    return [
        f"Decision budget {budget:g} s (`--decision-budget`): a round deciding more slowly is flagged "
        "(`over_budget` in `rounds.csv.gz`) and counted in the KPI `rounds_over_budget`; the simulation is "
        "the same as without it.",
        "",
    ]


def synthetic_lines(scenario: dict[str, Any]) -> list[str]:
    """The banner at the top of the report of a synthetic scenario: what is synthetic about it."""
    if not scenario.get("synthetic"):
        return []
    if scenario.get("name") == "toy":
        text = (
            "**Synthetic city, not Haikou.** Every number in this report comes from rpbench's built-in "
            "synthetic toy city: a grid road network and orders generated in code, no real data. "
            "`rpbench data fetch` gets the real Haikou data; `rpbench run` then runs the real peak hour."
        )
    elif scenario.get("name") == "haikou-day":
        text = (
            "**Synthetic orders.** The road network and each hour's order count are Haikou's, but the orders "
            "themselves are drawn: request times at random within each hour, origin-destination pairs from the "
            "08:00-09:00 OD rates of the month (no public full-day order list exists). The numbers describe "
            "this stand-in, not the real day."
        )
    else:
        text = "**Synthetic scenario** — not real order data (see the scenario label)."
    return [f"> {text}", ""]


def wall_lines(meta: dict[str, Any], styles: Styles | None = None) -> list[str]:
    """The run times of meta.json: each run's round loop (``wall_s``) and, where recorded (``prepare_s``)
    and above :data:`PREPARE_SHOWN_S`, its one-off preparation."""
    runs = meta.get("runs", {})
    walls = {r: v["wall_s"] for r, v in runs.items() if v.get("wall_s") is not None}
    prepares = {r: v["prepare_s"] for r, v in runs.items() if v.get("prepare_s") is not None}
    lines = []
    if walls:
        what = "Wall time of the round loop per run" if prepares else "Wall time per run"
        lines += [f"{what}: " + ", ".join(f"{run_label(r, styles)} {w:.2f} s" for r, w in walls.items()), ""]
    shown = {r: t for r, t in prepares.items() if t > PREPARE_SHOWN_S}
    if shown:
        lines += [
            "One-off preparation per run, once before its first round (loading or building predictions and "
            "caches, cache builds included): "
            + ", ".join(f"{run_label(r, styles)} {t:.2f} s" for r, t in shown.items()),
            "",
        ]
    return lines


def offline_notes(table: pd.DataFrame, meta: dict) -> list[str]:
    """What the offline columns of a table mean: the bound's proof and status, why Oracle-1's ratio can pass 1."""
    lines = []
    if "bound" in table.columns:
        status = meta.get("runs", {}).get("bound", {}).get("status", "optimal")
        proven = (
            "solved to proven optimality"
            if status == "optimal"
            else f"**not** solved to optimality ({status}): its value is the solver's dual bound"
        )
        lines.append(
            f"Upper bound: the maximum-weight matching over every pair rpbench's simulator can form, "
            f"each weighted by the largest saving it can realise (docs/bound.md), {proven}; "
            "`rpbench check` certifies every strategy pair against it."
        )
    if "oracle1" in table.columns:
        lines.append(ORACLE1_NOTE)
    return [" ".join(lines), ""] if lines else []


def _has_tabulate() -> bool:
    try:
        import tabulate  # noqa: F401
    except ImportError:
        return False
    return True


def write_report(
    folder: Path,
    name: str | None = None,
    dest: Path | None = None,
    *,
    figures: bool = True,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
    kpis_drawn: bool = False,
) -> Path:
    """Write ``report.md`` and its figures (:data:`FIGURES`, in ``formats``) into ``folder``, or into ``dest``
    (``folder`` is then only read); ``name``: the folder's final name, for the text.  ``figures=False``: a
    published unit of an evaluation, whose figures (and any left in ``dest``) are left out.  ``kpis_drawn``:
    the caller draws :data:`KPIS_PNG` itself (:func:`draw_kpi_figure`, in another process).  Returns the
    report's path."""
    dest = folder if dest is None else dest
    if figures:
        text = report_markdown(folder, name, figure_lines(folder, dest, formats, kpis_drawn=kpis_drawn))
    else:
        for figure in FIGURES:
            for suffix in (".png", *layout.VECTOR_SUFFIXES):
                (dest / figure).with_suffix(suffix).unlink(missing_ok=True)
        text = report_markdown(folder, name, UNIT_FIGURES)
    write_paper_tables(folder, dest)
    path = dest / "report.md"
    files.write_text(path, text)  # a command line or folder name with non-UTF-8 bytes is quoted escaped
    return path


def write_paper_tables(folder: Path, dest: Path) -> None:
    """``table.tex`` and ``table.csv``: the comparison table for a paper (:mod:`rpbench.report.tables`)."""
    meta = report_meta(folder)
    table = load_kpis(folder)
    styles = run_styles(meta)
    rows = table_rows(table)
    caption = (
        f"{meta['scenario']['label']}: rpbench {meta['versions']['rpbench']}, solver preset {meta['preset']['name']}"
    )
    note = bracket_line(table, simulated_runs(meta, map(str, table.columns)), fmt, styles)
    tex = latex_table(table, rows, fmt, caption=caption, unproven=unproven_runs(folder), mark=UNPROVEN_MARK,
                      styles=styles, note=note)  # fmt: skip
    files.write_text(dest / layout.TABLE_TEX, tex)
    csv_table(table, rows, styles).to_csv(dest / layout.TABLE_CSV)


def draw_kpi_figure(folder: Path, dest: Path, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS) -> Path:
    """:data:`KPIS_PNG` of ``folder``, the headline KPIs of its table, drawn into ``dest`` in ``formats``."""
    meta = report_meta(folder)
    table, styles = load_kpis(folder), run_styles(meta)
    return kpi_figure(table, dest / KPIS_PNG, meta["scenario"]["label"], fmt, styles, formats=formats)


def figure_lines(
    folder: Path, dest: Path, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS, *, kpis_drawn: bool = False
) -> list[str]:
    """Draw the figures of ``folder`` into ``dest`` in ``formats`` (:data:`KPIS_PNG` unless ``kpis_drawn``);
    return the report's figure section embedding them (the same whichever formats)."""
    meta = report_meta(folder)
    sc = meta["scenario"]
    table = load_kpis(folder)
    styles = run_styles(meta)
    if not kpis_drawn:
        draw_kpi_figure(folder, dest, formats)
    no_ratio = (
        "; the competitive ratio is drawn as its interval, from saving / upper bound (bar) to saving / best known "
        "schedule (the segment above it)"
        if "bound" in table.columns
        else "; without an upper bound run the competitive ratio is drawn only as saving / best known schedule"
    )
    lines = [
        "## Figures",
        "",
        f"{FORMATS_NOTE}; the comparison table is `{layout.TABLE_TEX}` (LaTeX, booktabs) and `{layout.TABLE_CSV}` "
        "(raw values).",
        "",
        f"![headline KPIs per run]({KPIS_PNG})",
        "",
        "Headline KPIs of the comparison table, one bar per run; a panel leaves out the runs without that KPI "
        f"(offline runs have no response rate nor pick-up time){no_ratio}.",
        "",
    ]
    for suffix in (".png", *layout.VECTOR_SUFFIXES):  # a light copy's timeline would no longer be the folder's
        (dest / TIMELINE_PNG).with_suffix(suffix).unlink(missing_ok=True)
    timeline = timeline_of(folder)
    if isinstance(timeline, str):
        lines += [timeline, ""]
    else:
        timeline_figure(
            timeline.table,
            dest / TIMELINE_PNG,
            sc["label"],
            hours=timeline.hours,
            start=timeline.start,
            bin_s=timeline.bin_s,
            horizon_s=timeline.horizon_s,
            styles=styles,
            formats=formats,
        )
        unit = "hours" if timeline.hours else "minutes"
        left_out = (
            f" The offline runs ({', '.join(run_label(r, styles) for r in timeline.offline)}) pair orders after the "
            "fact and have no event log: they are not drawn."
            if timeline.offline
            else ""
        )
        lines += [
            f"![timeline of the period]({TIMELINE_PNG})",
            "",
            f"Over the period, per strategy (from its event log): passengers waiting (requested, not yet "
            f"assigned nor cancelled), being served (assigned, not yet dropped off) and riding pooled (on "
            f"board with their partner aboard), each the mean over {timeline.bin_s / 60:g}-minute bins, and "
            f"the passengers cancelled so far; {unit} since the scenario start, the dotted line where "
            f"requests stop.{left_out}",
            "",
        ]
    hourly_png = hourly_plot(folder, dest, formats)
    if hourly_png is not None:
        lines += [
            "### Per hour",
            "",
            "KPIs by request hour (saving of a pair counted in the hour of its earlier request). The upper "
            "bound's line is its whole-period matching split the same way: per hour it describes that "
            "matching and is not itself a bound.",
            "",
            f"![per-hour comparison]({hourly_png.name})",
            "",
        ]
    return lines


@dataclass(frozen=True)
class Timeline:
    """What :func:`rpbench.report.plots.timeline_figure` draws, read off a folder's event logs."""

    table: pd.DataFrame  # run, state, t_s, value
    bin_s: float
    hours: bool
    start: str | None  # the scenario start's clock time (HH:MM)
    horizon_s: float
    offline: list[str]  # runs without an event log, in the folder's order


def timeline_of(folder: Path) -> Timeline | str:
    """The timeline of every simulation run of ``folder`` (:func:`rpbench.results.metrics.state_spells`,
    binned by :data:`TIMELINE_BINS_S`), or the sentence saying why there is none."""
    meta = report_meta(folder)
    sc = meta["scenario"]
    if not results.run_names(folder):
        return (
            "No timeline: it is drawn from the runs' event logs (`runs/<run>/events.csv.gz`), which this "
            "published light copy leaves out; rerun the command above for the full folder."
        )
    order = list(dict.fromkeys([*meta.get("strategies", []), *results.run_names(folder)]))
    logs = {r: folder / "runs" / r / "events.csv.gz" for r in order}
    simulated = [r for r in order if logs[r].is_file()]
    if not simulated:
        return "No timeline: every run of this folder is offline (no event log to draw)."
    spells, end = {}, 0.0
    try:
        for r in simulated:
            events = results.read_csv(logs[r])
            spells[r] = state_spells(events)
            end = max(end, float(events["t_s"].max()) if len(events) else 0.0)
    except (ResultsError, KeyError, ValueError) as exc:  # a damaged log: `rpbench check` says what is wrong
        return f"No timeline: an event log cannot be read ({exc})."
    horizon = float(sc.get("horizon_s") or end)
    span = max(end, horizon, 1.0)
    bin_s = next((w for w in TIMELINE_BINS_S if span / w <= TIMELINE_MAX_BINS), TIMELINE_BINS_S[-1])
    edges = np.arange(0.0, span + bin_s, bin_s)
    middle = (edges[:-1] + edges[1:]) / 2
    frames = []
    for r in simulated:
        for state in TIMELINE_STATES:
            if state == "cancelled":  # a running total: the count at each bin's end, from 0 at the start
                t, value = edges, count_at(spells[r][state], edges).astype(float)
            else:
                t, value = middle, mean_count(spells[r][state], edges)
            frames.append(pd.DataFrame({"run": r, "state": state, "t_s": t, "value": value}))
    start = sc.get("start_time")
    return Timeline(
        table=pd.concat(frames, ignore_index=True),
        bin_s=bin_s,
        hours=horizon > LONG_SCENARIO_S,
        start=pd.Timestamp(start).strftime("%H:%M") if start else None,
        horizon_s=horizon,
        offline=[r for r in order if r not in simulated],
    )


def hourly_plot(folder: Path, dest: Path | None = None, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS) -> Path | None:
    """``hourly.png`` (into ``dest``, default ``folder``; in ``formats``) when the folder covers more than two
    hours (full-day and trace scenarios)."""
    path = folder / "hourly.csv"
    if not path.is_file():
        return None
    hourly = pd.read_csv(path)
    if hourly.empty or hourly["hour"].nunique() <= 2:
        return None
    meta = report_meta(folder)
    path = (folder if dest is None else dest) / HOURLY_PNG
    return hourly_figure(hourly, path, meta["scenario"]["label"], run_styles(meta), formats=formats)


def findings(table: pd.DataFrame) -> dict[str, bool] | None:
    """The paper's headline claims on one KPI table (KPI rows x run columns), or None without FL/MB/RTV."""
    if not {"fl", "mb", "rtv"} <= set(table.columns):
        return None
    col = table.loc
    return {
        "FL saves the most distance (vs MB, RTV)": bool(
            col["total_saving_km", "fl"] > max(col["total_saving_km", "mb"], col["total_saving_km", "rtv"])
        ),
        "FL has the lowest average detour (vs MB, RTV)": bool(
            col["avg_detour_m", "fl"] < min(col["avg_detour_m", "mb"], col["avg_detour_m", "rtv"])
        ),
        "FL has a lower response rate (vs MB, RTV)": bool(
            col["response_rate", "fl"] < min(col["response_rate", "mb"], col["response_rate", "rtv"])
        ),
    }


def check_metrics(metrics: list[str] | None) -> list[str] | None:
    """Validate a user's KPI selection against the known KPI names."""
    if metrics is None:
        return None
    known = KPI_ORDER + EXTRA_KPIS + list(DERIVED_KPIS) + ["wall_s"]
    renamed = [m for m in metrics if m in LEGACY_KPIS]
    if renamed:
        raise ResultsError(f"metric {renamed[0]!r} is named {LEGACY_KPIS[renamed[0]]!r} now")
    unknown = [m for m in metrics if m not in known]
    if unknown or not metrics:
        raise ResultsError(f"unknown metric {unknown[0] if unknown else '(none)'!r}; known metrics: {', '.join(known)}")
    return metrics


def selected_markdown(table: pd.DataFrame, styles: Styles | None = None) -> str:
    cols = list(table.columns)
    out = ["| Metric | " + " | ".join(markdown_cell(run_label(c, styles)) for c in cols) + " |"]
    out.append("|---|" + "---:|" * len(cols))
    for k in table.index:
        out.append(f"| {KPI_LABELS.get(k, k)} | " + " | ".join(fmt(k, table.loc[k, c]) for c in cols) + " |")
    return "\n".join(out)
