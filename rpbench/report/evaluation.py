"""An evaluation folder's tables and report, from its (day, seed) children alone.

``units.csv`` gathers every child's KPI table (the ratio and bracket rows included); ``leaderboard.csv``
and ``paired.csv`` are :func:`rpbench.report.leaderboard.leaderboard` and
:func:`~rpbench.report.leaderboard.paired` of it under the protocol recorded in meta.json, the leaderboard
with its ranking (:mod:`rpbench.results.ranking`), so the checker recomputes all three from the children.
A protocol ranking by the competitive ratio against the bound gets its other end, saving / best known
schedule, beside it (:func:`board_metrics`): the ratio is an interval.

The tables rank the runs the units hold (:func:`evaluation_runs`), each protocol entry under the name its run
has in the units: a ``module:Class`` plug-in runs under its class's name, which the protocol's text is not.
report.md and table.tex are :func:`evaluation_report` of the tables, text only, so that the checker
regenerates them and compares; :func:`write_evaluation_report` also draws the figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench import files, results
from rpbench.exceptions import ResultsError
from rpbench.plugins import is_spec
from rpbench.report.comparison import fmt
from rpbench.report.leaderboard import RATIO_OF_MEANS, Bootstrap, leaderboard, paired
from rpbench.report.plots import FORMATS_NOTE, leaderboard_figure, seeds_by_day_figure
from rpbench.report.tables import booktabs, latex_escape
from rpbench.results import layout
from rpbench.results.legacy import current_names
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.ranking import RANKING_COLUMNS, ranked, run_groups
from rpbench.results.ratios import RATIO_KPIS
from rpbench.results.read import load_kpis
from rpbench.results.runs import markdown_cell, run_label, run_styles
from rpbench.spec import DEFAULT_FIGURE_FORMATS

#: The leaderboard's figure (and on request its SVG and PDF beside it).
LEADERBOARD_PNG = "leaderboard.png"


def unit_name(day: str | None, seed: int) -> str:
    """The child folder of a (day, seed) unit."""
    return f"{day}_seed{seed}" if day else f"seed{seed}"


def units_table(folder: Path) -> pd.DataFrame:
    """Tidy (day, seed, run, kpi, value) over the children meta.json lists, in its order."""
    meta = results.read_meta(folder)
    frames = []
    for name in meta.get("children", []):
        child = folder / name
        if not (child / layout.KPIS).is_file():
            raise ResultsError(f"{str(child)!r}: the evaluation's unit has no results (resume the evaluation)")
        args = results.read_meta(child)["scenario"].get("args", {})
        wide = load_kpis(child)
        tidy = wide.reset_index().melt(id_vars="kpi", var_name="run", value_name="value")
        frames.append(tidy.assign(day=args.get("date") or "", seed=int(args.get("seed", 0))))
    if not frames:
        raise ResultsError(f"{str(folder)!r} holds no evaluation units")
    return pd.concat(frames, ignore_index=True)[["day", "seed", "run", "kpi", "value"]]


def bootstrap_of(meta: dict) -> Bootstrap:
    boot = meta["protocol"]["bootstrap"]
    return Bootstrap(resamples=int(boot["resamples"]), seed=int(boot["seed"]), level=float(boot["level"]))


def board_metrics(metrics: list[str]) -> list[str]:
    """The leaderboard's metrics: the protocol's, ``competitive_ratio_best_known`` added after
    ``competitive_ratio_bound`` (the two ends of the competitive ratio's interval)."""
    if "competitive_ratio_bound" in metrics and "competitive_ratio_best_known" not in metrics:
        at = metrics.index("competitive_ratio_bound") + 1
        return [*metrics[:at], "competitive_ratio_best_known", *metrics[at:]]
    return list(metrics)


def unit_records(folder: Path) -> list[dict]:
    """Every unit's run records (meta.json's ``runs``), in the order meta.json lists the units."""
    meta = results.read_meta(folder)
    return [results.read_meta(folder / name).get("runs") or {} for name in meta.get("children", [])]


def entry_run(entry: str, records: Mapping[str, Any]) -> str | None:
    """The run a protocol's strategy ``entry`` ran as in one unit (``records``: the unit's meta.json ``runs``):
    the run of that name (a built-in's name read case-insensitively, as the command line reads it), else the
    run whose recorded ``source`` is the entry (a ``module:Class`` plug-in runs under its class's name); None
    when the unit holds neither."""
    base, sep, settings = entry.partition("@")
    typed = entry if is_spec(base) else f"{base.strip().lower()}{sep}{settings}"
    for name in (entry, typed):
        if isinstance(records.get(name), Mapping):
            return name
    found = [n for n, r in records.items() if isinstance(r, Mapping) and r.get("source") == entry]
    return found[0] if len(found) == 1 else None


def evaluation_runs(strategies: Sequence[str], units: Sequence[Mapping[str, Any]]) -> list[str]:
    """The runs of an evaluation, in the protocol's order: each of ``strategies`` under the name the units give
    its run (:func:`entry_run`; the entry itself when no unit holds it), then any other run a unit holds
    (``units``: each unit's meta.json ``runs``).  A run the units hold is never left out of the tables."""
    runs = []
    for entry in strategies:
        found = (entry_run(entry, records) for records in units)
        runs.append(next((name for name in found if name is not None), entry))
    held = (str(name) for records in units for name in records)
    return list(dict.fromkeys([*runs, *held]))


def tables(folder: Path) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(units, leaderboard with its ranking, paired) recomputed from the children."""
    meta = results.read_meta(folder)
    units = units_table(folder)
    units["day"] = units["day"].fillna("").astype(str)
    records = unit_records(folder)
    runs = evaluation_runs(meta["protocol"]["strategies"], records)
    metrics = list(meta["protocol"]["metrics"])
    boot = bootstrap_of(meta)
    groups = run_groups(records, runs)
    board = ranked(leaderboard(units, runs, board_metrics(metrics), boot), groups, metrics[0], runs)
    simulated = [r for r in runs if groups[r] != "offline"]
    return units, board, paired(units, simulated, metrics, boot)


def read_leaderboard(folder: Path) -> pd.DataFrame:
    """``leaderboard.csv`` as today's rpbench names it, with its ranking (recomputed from the units' records
    for a leaderboard written before rpbench recorded one)."""
    board = current_names(results.read_csv(folder / layout.LEADERBOARD))
    if set(RANKING_COLUMNS) <= set(board.columns):
        return board
    protocol = results.read_meta(folder)["protocol"]
    records = unit_records(folder)
    runs = evaluation_runs(protocol["strategies"], records)
    return ranked(board, run_groups(records, runs), protocol["metrics"][0], runs)


def write_evaluation_tables(folder: Path) -> pd.DataFrame:
    """Write units.csv, leaderboard.csv and paired.csv (each whole or not at all); returns the leaderboard."""
    units, board, pairs = tables(folder)
    for name, table in ((layout.UNITS, units), (layout.LEADERBOARD, board), (layout.PAIRED, pairs)):
        tmp = folder / f".{name}.partial"
        table.to_csv(tmp, index=False)
        tmp.replace(folder / name)
    return board


@dataclass(frozen=True)
class EvaluationReport:
    """An evaluation's report as text: report.md, and its leaderboard as LaTeX (table.tex)."""

    markdown: str
    tex: str


def write_evaluation_report(
    folder: Path, name: str | None = None, *, figures: bool = True, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS
) -> Path:
    """report.md (the protocol, the leaderboard ranked by its first metric, the paired comparisons of that
    metric, where each unit's folder is), its figures (in ``formats``) and table.tex, from the folder's tables.
    ``figures=False`` leaves the figures as they are (the text of the report does not depend on them)."""
    meta = results.read_meta(folder)
    protocol = meta["protocol"]
    board = read_leaderboard(folder)
    units = results.read_csv(folder / layout.UNITS)
    units["day"] = units["day"].astype(object).fillna("").astype(str)  # undated units have no day
    runs = evaluation_runs(protocol["strategies"], unit_records(folder))
    styles = run_styles(results.read_meta(folder / meta["children"][0]))
    if figures:
        _draw_figures(folder, board, units, protocol, runs, styles, formats)
    report = evaluation_report(folder, name, board, results.read_csv(folder / layout.PAIRED), units, runs)
    files.write_text(folder / layout.TABLE_TEX, report.tex)
    path = folder / layout.REPORT
    files.write_text(path, report.markdown)
    return path


def evaluation_report(
    folder: Path, name: str | None, board: pd.DataFrame, pairs: pd.DataFrame, units: pd.DataFrame, runs: Sequence[str]
) -> EvaluationReport:
    """report.md and table.tex of the evaluation in ``folder`` from its tables (``board``: the leaderboard with
    its ranking, ``pairs``: the paired tests, ``units``: every unit's KPIs, day "" when undated) and its
    ``runs`` (:func:`evaluation_runs`); reads only meta.json, draws nothing."""
    meta = results.read_meta(folder)
    protocol = meta["protocol"]
    styles = run_styles(results.read_meta(folder / meta["children"][0]))
    metrics = list(protocol["metrics"])
    rank = metrics[0]
    level = f"{protocol['bootstrap']['level']:.0%}"
    unit = "days" if protocol.get("dates") else "seeds"  # the independent draws: the bootstrap's clusters
    lines = [
        f"# rpbench evaluation: protocol `{protocol['name']}` version {protocol['version']}",
        "",
        f"- {protocol['description']}",
        f"- scenario `{protocol['scenario']}`,"
        f" dates {protocol.get('dates') or '(undated)'}, sample "
        f"{protocol.get('sample')}, seeds {', '.join(map(str, protocol['seeds']))}; {len(meta['children'])} runs "
        f"per strategy; solver presets `{protocol['preset']}` / `{protocol.get('oracle_preset') or protocol['preset']}`"
        " (offline runs)",
        f"- rpbench {meta['versions']['rpbench']}, commit `{meta.get('git_commit')}`; protocol digest "
        f"`{protocol['digest']}`",
        "",
    ]
    if meta.get("command"):
        lines += ["Command:", "", f"    {meta['command']}", ""]
    lines += [
        "## Leaderboard",
        "",
        f"Mean over the (day, seed) runs and its {level} interval: a two-stage bootstrap over days, then seeds "
        f"within a day (undated: over seeds; {protocol['bootstrap']['resamples']} resamples, generator seed "
        f"{protocol['bootstrap']['seed']}). Ranked by {KPI_LABELS.get(rank, rank)}: the online runs first, then "
        "the clairvoyant runs apart (they read the day's orders before they were revealed), then the offline "
        "runs (references, not schedules); `leaderboard.csv` records each run's group and rank. The competitive "
        "ratio is an interval, from the mean over runs of saving / upper bound to the mean of saving / best known "
        "schedule (means of ratios); the last column is mean saving / mean bound saving (a ratio of means).",
        "",
    ]
    head, body = leaderboard_rows(board, protocol, styles, runs)
    lines += ["| " + " | ".join(map(markdown_cell, head)) + " |", "|---|" + "---:|" * (len(head) - 1)]
    lines += ["| " + " | ".join(map(markdown_cell, row)) + " |" for row in body]
    lines += ["", *_figure_lines(units, protocol, runs, level)]
    sel = pairs[pairs["kpi"] == rank]
    if len(sel):
        lines += [
            f"## Paired differences: {KPI_LABELS.get(rank, rank)}",
            "",
            f"A - B over the same (day, seed) runs, mean and {level} bootstrap interval; Wilcoxon signed-rank "
            f"test (two-sided) of the per-{unit[:-1]} mean differences; {unit} where A is above / below B. "
            f"{smallest_p_text(_clusters(units, unit), unit)}",
            "",
            f"| A | B | mean A - B | interval | Wilcoxon p | {unit} A above / below / tied |",
            "|---|---|---:|---:|---:|---:|",
        ]
        for _, r in sel.iterrows():
            lines.append(
                f"| {markdown_cell(run_label(r['a'], styles))} | {markdown_cell(run_label(r['b'], styles))} | "
                f"{fmt(rank, r['mean_diff'])} | "
                f"[{fmt(rank, r['ci_low'])}, {fmt(rank, r['ci_high'])}] | {r['wilcoxon_p']:.3g} | "
                f"{int(r['days_a_above'])} / {int(r['days_a_below'])} / {int(r['days_tied'])} |"
            )
        lines += ["", f"Every metric's paired differences: `{layout.PAIRED}`; every run's KPIs: `{layout.UNITS}`.", ""]
    lines += [
        "Each (day, seed) run is an ordinary results folder: `rpbench check PATH`, PATH being the path to "
        f"`{name or folder.name}`, checks them all and recomputes these tables from them.",
        "",
    ]
    caption = f"rpbench evaluation {protocol['name']} version {protocol['version']}: mean [{level} interval]"
    latex = [[latex_escape(cell) for cell in row] for row in [head, *body]]
    tex = booktabs(latex[0], latex[1:], caption=caption, what="the leaderboard")
    return EvaluationReport("\n".join(lines), tex)


def leaderboard_rows(
    board: pd.DataFrame, protocol: dict, styles, runs: Sequence[str] | None = None
) -> tuple[list[str], list[list[str]]]:
    """The leaderboard as printed: a header (rank, strategy, each metric, the ratio of means) and a row per run
    in the order of its recorded ranking (:mod:`rpbench.results.ranking`), each cell "mean [low, high]" as the
    report formats the KPI; a run of ``runs`` (default: the protocol's strategies) without rows comes last."""
    cols = [*board_metrics(list(protocol["metrics"])), RATIO_OF_MEANS]
    head = ["Rank", "Strategy"] + [KPI_LABELS.get(k, "Saving: ratio of means") for k in cols]
    first = board.drop_duplicates("run").set_index("run")
    order = [str(r) for r in first.sort_values("rank", kind="stable").index]
    order += [r for r in (protocol["strategies"] if runs is None else runs) if r not in order]
    cell = board.set_index(["run", "kpi"])
    body = []
    for run in order:
        row = [_rank_cell(run, first), run_label(run, styles)]
        offline = run in first.index and first.loc[run, "group"] == "offline"
        for k in cols:
            if (run, k) in cell.index and not (offline and k in RATIO_KPIS):  # an older leaderboard ranked its 1.000
                r = cell.loc[(run, k)]
                key = "competitive_ratio_bound" if k == RATIO_OF_MEANS else k
                row.append(f"{fmt(key, r['mean'])} [{fmt(key, r['ci_low'])}, {fmt(key, r['ci_high'])}]")
            else:
                row.append("/")
        body.append(row)
    return head, body


def smallest_p_text(n: int, unit: str) -> str:
    """What the paired test can say with ``n`` independent ``unit``: the exact two-sided signed-rank test's
    smallest p, 2 / 2^n, reached when every one of them differs the same way."""
    if n < 1:
        return ""
    return (
        f"With {n} {unit} the exact test's smallest p is 2 / 2^{n} = {2.0 / 2.0**n:.3g} (A above B on every "
        f"one of them): a p near it says as much as {n} {unit} can."
    )


def _clusters(units: pd.DataFrame, unit: str) -> int:
    """The number of independent draws: the days of a dated protocol, else the seeds."""
    column = "day" if unit == "days" else "seed"
    return int(units[column].nunique()) if column in units.columns else 0


def _rank_cell(run: str, first: pd.DataFrame) -> str:
    """A run's place in the printed leaderboard: "online 1", "clairvoyant 1" (ranked apart), or "reference"
    for an offline run (``first``: the leaderboard's first row per run, with its group and rank)."""
    if run not in first.index:
        return "/"
    group = str(first.loc[run, "group"])
    if group == "offline":
        return "reference"
    peers = first[first["group"] == group]["rank"]
    return f"{group} {int((peers < first.loc[run, 'rank']).sum()) + 1}"


def _figure_lines(units: pd.DataFrame, protocol: dict, runs: Sequence[str], level: str) -> list[str]:
    """The report lines embedding the figures :func:`_draw_figures` draws (the per-day one only when the units
    hold a value of the ranking metric)."""
    lines = [
        f"![leaderboard: mean and {level} interval]({LEADERBOARD_PNG})",
        "",
    ]
    rank = protocol["metrics"][0]
    label = KPI_LABELS.get(rank, rank)
    if not _by_day_values(units, rank, runs).empty:
        lines += [f"![{label} per day]({by_day_png(rank)})", ""]
    lines += [
        f"{FORMATS_NOTE}; the leaderboard is `{layout.TABLE_TEX}` (LaTeX, booktabs) and `{layout.LEADERBOARD}` "
        "(raw values).",
        "",
    ]
    return lines


def by_day_png(metric: str) -> str:
    """The figure of ``metric`` per day (each run's mean over the day's seeds, their range as a bar)."""
    return f"by_day_{metric}.png"


def _by_day_values(units: pd.DataFrame, metric: str, runs: Sequence[str]) -> pd.DataFrame:
    return units[(units["kpi"] == metric) & units["run"].isin(list(runs)) & units["value"].notna()]


def _draw_figures(
    folder: Path,
    board: pd.DataFrame,
    units: pd.DataFrame,
    protocol: dict,
    runs: Sequence[str],
    styles,
    formats: Sequence[str],
) -> None:
    """The leaderboard (one panel per metric) and the first metric per day, each in ``formats``."""
    title = f"rpbench evaluation {protocol['name']} version {protocol['version']}"
    level = f"{protocol['bootstrap']['level']:.0%}"
    metrics = board_metrics(list(protocol["metrics"]))
    leaderboard_figure(
        board, metrics, folder / LEADERBOARD_PNG, f"{title}: mean and {level} interval", styles, formats=formats
    )
    rank = protocol["metrics"][0]
    label = KPI_LABELS.get(rank, rank)
    seeds_by_day_figure(units, rank, runs, folder / by_day_png(rank),
                        f"{title}: {label}, mean over the seeds of each day (bars: their range)",
                        styles, formats=formats)  # fmt: skip
