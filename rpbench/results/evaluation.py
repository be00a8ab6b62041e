"""An evaluation folder's tables and report, from its (day, seed) children alone.

``units.csv`` gathers every child's KPI table (the competitive ratio rows included); ``leaderboard.csv``
and ``paired.csv`` are :func:`rpbench.results.leaderboard.leaderboard` and
:func:`~rpbench.results.leaderboard.paired` of it under the protocol recorded in meta.json, so the checker
recomputes all three from the children.
"""

from __future__ import annotations

from collections.abc import Collection
from pathlib import Path

import pandas as pd

from rpbench import files, results
from rpbench.exceptions import ResultsError
from rpbench.results import layout
from rpbench.results.leaderboard import RATIO_OF_MEANS, Bootstrap, leaderboard, paired
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.plots import leaderboard_figure, seeds_by_day_figure
from rpbench.results.report import fmt, load_kpis
from rpbench.results.runs import clairvoyant_runs, markdown_cell, run_label, run_styles
from rpbench.results.tables import booktabs, latex_escape

#: The leaderboard's figure (and its SVG and PDF beside it).
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


def tables(folder: Path) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(units, leaderboard, paired) recomputed from the children."""
    meta = results.read_meta(folder)
    units = units_table(folder)
    units["day"] = units["day"].fillna("").astype(str)
    runs = list(meta["protocol"]["strategies"])
    metrics = list(meta["protocol"]["metrics"])
    boot = bootstrap_of(meta)
    board = leaderboard(units, runs, metrics, boot)
    online = [r for r in runs if results.read_meta(folder / meta["children"][0])["runs"][r]["kind"] == "simulation"]
    return units, board, paired(units, online, metrics, boot)


def summarize(folder: Path) -> None:
    """Write units.csv, leaderboard.csv and paired.csv (each whole or not at all)."""
    units, board, pairs = tables(folder)
    for name, table in ((layout.UNITS, units), (layout.LEADERBOARD, board), (layout.PAIRED, pairs)):
        tmp = folder / f".{name}.partial"
        table.to_csv(tmp, index=False)
        tmp.replace(folder / name)


def write_evaluation_report(folder: Path, name: str | None = None) -> Path:
    """report.md: the protocol, the leaderboard (mean [interval]) ranked by its first metric, the paired
    comparisons of that metric, and where each unit's folder is."""
    meta = results.read_meta(folder)
    protocol = meta["protocol"]
    board = results.read_csv(folder / layout.LEADERBOARD)
    pairs = results.read_csv(folder / layout.PAIRED)
    child = results.read_meta(folder / meta["children"][0])
    styles = run_styles(child)
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
        f"{protocol['bootstrap']['seed']}). Ranked by {KPI_LABELS.get(rank, rank)}. The competitive ratio is the "
        "mean over runs of saving / bound (a mean of ratios); the last column is mean saving / mean bound "
        "saving (a ratio of means).",
        "",
    ]
    apart = clairvoyant_runs(child)
    if apart & set(protocol["strategies"]):
        lines[-2] += " Clairvoyant runs read the day's orders before they were revealed: they are ranked apart, last."
    head, body = leaderboard_rows(board, protocol, styles, clairvoyant=apart)
    lines += ["| " + " | ".join(map(markdown_cell, head)) + " |", "|---|" + "---:|" * (len(head) - 1)]
    lines += ["| " + " | ".join(map(markdown_cell, row)) + " |" for row in body]
    lines += ["", *_figure_lines(folder, board, protocol, styles, level)]
    sel = pairs[pairs["kpi"] == rank]
    if len(sel):
        lines += [
            f"## Paired differences: {KPI_LABELS.get(rank, rank)}",
            "",
            f"A - B over the same (day, seed) runs, mean and {level} bootstrap interval; Wilcoxon signed-rank "
            f"test (two-sided) of the per-{unit[:-1]} mean differences; {unit} where A is above / below B.",
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
    files.write_text(folder / layout.TABLE_TEX, booktabs(latex[0], latex[1:], caption=caption, what="the leaderboard"))
    path = folder / layout.REPORT
    files.write_text(path, "\n".join(lines))
    return path


def leaderboard_rows(
    board: pd.DataFrame, protocol: dict, styles, *, clairvoyant: Collection[str] = ()
) -> tuple[list[str], list[list[str]]]:
    """The leaderboard as printed: a header (strategy, each metric, the ratio of means) and a row per run,
    ranked by the protocol's first metric, each cell "mean [low, high]" as the report formats the KPI.  The
    ``clairvoyant`` runs (they read the future) are ranked apart, after the others."""
    metrics = list(protocol["metrics"])
    cols = [*metrics, RATIO_OF_MEANS]
    head = ["Strategy"] + [KPI_LABELS.get(k, "Saving: ratio of means") for k in cols]
    order = board[board["kpi"] == metrics[0]].sort_values("mean", ascending=False)["run"].tolist()
    order = [r for r in order if r not in clairvoyant] + [r for r in order if r in clairvoyant]
    order += [r for r in protocol["strategies"] if r not in order]
    cell = board.set_index(["run", "kpi"])
    body = []
    for run in order:
        row = [run_label(run, styles)]
        for k in cols:
            if (run, k) in cell.index:
                r = cell.loc[(run, k)]
                key = "competitive_ratio_bound" if k == RATIO_OF_MEANS else k
                row.append(f"{fmt(key, r['mean'])} [{fmt(key, r['ci_low'])}, {fmt(key, r['ci_high'])}]")
            else:
                row.append("/")
        body.append(row)
    return head, body


def _figure_lines(folder: Path, board: pd.DataFrame, protocol: dict, styles, level: str) -> list[str]:
    """Draw the leaderboard and the first metric per day; return the report lines embedding them."""
    title = f"rpbench evaluation {protocol['name']} version {protocol['version']}"
    leaderboard_figure(board, protocol["metrics"], folder / LEADERBOARD_PNG, f"{title}: mean and {level} interval",
                       styles)  # fmt: skip
    lines = [
        f"![leaderboard: mean and {level} interval]({LEADERBOARD_PNG})",
        "",
    ]
    rank = protocol["metrics"][0]
    units = results.read_csv(folder / layout.UNITS)
    units["day"] = units["day"].astype(object).fillna("").astype(str)  # undated units have no day
    name = f"by_day_{rank}.png"
    label = KPI_LABELS.get(rank, rank)
    drawn = seeds_by_day_figure(units, rank, protocol["strategies"], folder / name,
                                f"{title}: {label}, mean over the seeds of each day (bars: their range)",
                                styles)  # fmt: skip
    if drawn is not None:
        lines += [f"![{label} per day]({name})", ""]
    lines += [
        f"Every figure is also beside its PNG as SVG and PDF; the leaderboard is `{layout.TABLE_TEX}` (LaTeX, "
        f"booktabs) and `{layout.LEADERBOARD}` (raw values).",
        "",
    ]
    return lines
