"""Reports rendered from result files alone (tables now; plots in rpbench.results.plots).

:func:`load_kpis` reads a results folder's tidy ``kpis.csv`` into the wide
KPI x run table; :func:`text_table` / :func:`markdown_table` format it in
the paper's Table 2 layout (strategies as columns); :func:`write_report`
writes ``report.md`` into the folder.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import paper, results
from rpbench.exceptions import ResultsError
from rpbench.results.metrics import EXTRA_KPIS, KPI_LABELS, KPI_ORDER
from rpbench.results.plots import hourly_figure
from rpbench.results.runs import Styles, run_label, run_styles

#: Competitive-ratio rows: KPI name -> the oracle run whose total saving is the denominator.
#: Ratio rows: KPI name -> the offline run whose total saving is the denominator.  Only the first is a
#: competitive ratio: the bound is proven (docs/bound.md); Oracle-1 is the paper's reference.
RATIO_ROWS = {"competitive_ratio_bound": "bound", "competitive_ratio": "oracle1"}
#: One line under every table with an Oracle-1 column: why its ratio can exceed 1.
ORACLE1_NOTE = (
    "Oracle-1 (the paper's) pairs only orders requested within K̄ of each other, while the strategies "
    "also pair en route, so a strategy can save more than Oracle-1: the saving / Oracle-1 row is a "
    "reference, not a competitive ratio; the competitive ratio divides by the proven upper bound."
)
#: Marks the column of a run whose numbers rest on solver answers not proven optimal (see :func:`unproven_runs`).
UNPROVEN_MARK = "*"
_DECIMALS = {
    "response_rate": 2,
    "pairing_ratio": 2,
    "competitive_ratio": 3,
    "competitive_ratio_bound": 3,
    "pairing_ratio_of_orders": 2,
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


def load_kpis(folder: Path) -> pd.DataFrame:
    """Wide KPI table (rows = KPI keys, columns = runs in meta.json's order)."""
    meta = results.read_meta(folder)
    tidy = results.read_csv(folder / "kpis.csv")
    missing = {"run", "kpi", "value"} - set(tidy.columns)
    if missing:
        raise ResultsError(f"{str(folder / 'kpis.csv')!r} lacks column(s) {', '.join(sorted(missing))}")
    wide = tidy.pivot(index="kpi", columns="run", values="value")
    order = [r for r in meta.get("strategies", []) if r in wide.columns] + [
        r for r in wide.columns if r not in meta.get("strategies", [])
    ]
    return with_competitive_ratios(wide[order].drop(index=list(RATIO_ROWS), errors="ignore"))


def with_competitive_ratios(wide: pd.DataFrame) -> pd.DataFrame:
    """Add a saving / offline-saving row for each of :data:`RATIO_ROWS`' runs present (the bound's is the
    competitive ratio; the paper's §4 reports FL = 63.2 % of Oracle-1)."""
    for row, oracle in RATIO_ROWS.items():
        if oracle in wide.columns and "total_saving_km" in wide.index:
            best = wide.loc["total_saving_km", oracle]
            wide.loc[row] = wide.loc["total_saving_km"] / best if best else np.nan
    return wide


def table_rows(table: pd.DataFrame) -> list[str]:
    return [k for k in KPI_ORDER if k in table.index] + [k for k in RATIO_ROWS if k in table.index]


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
    body = [[KPI_LABELS.get(k, k)] + [fmt(k, table.loc[k, c]) for c in cols] for k in rows]
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
    out = [
        "| Metric | "
        + " | ".join(run_label(c, styles) + ("\\" + UNPROVEN_MARK if c in unproven else "") for c in cols)
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
                    if k not in RATIO_ROWS
                    else (paper.FL_COMPETITIVE_RATIO if c == "fl" and k == "competitive_ratio" else float("nan"))
                )
                cell += f" ({fmt(k, ref)})"
            cells.append(cell)
        out.append(f"| {KPI_LABELS.get(k, k)} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def solver_summary(folder: Path) -> pd.DataFrame | None:
    """Per run: rounds solved, model size and solve time percentiles, statuses."""
    path = folder / "rounds.csv.gz"
    if not path.is_file():
        return None
    rounds = pd.read_csv(path)
    if rounds.empty:
        return None
    g = rounds.groupby("run", sort=False)
    return pd.DataFrame(
        {
            "rounds": g.size(),
            "mean cols": g["cols"].mean().round(1),
            "max cols": g["cols"].max(),
            "strategy build p50 (ms)": (g["strategy_build_s"].median() * 1e3).round(3),
            "solve p50 (ms)": (g["solve_s"].median() * 1e3).round(3),
            "solve p95 (ms)": (g["solve_s"].quantile(0.95) * 1e3).round(3),
            "solver total (s)": (g["solver_build_s"].sum() + g["solve_s"].sum() + g["extract_s"].sum()).round(3),
            "not optimal": g["status"].apply(lambda s: int((s != "optimal").sum())),
            "tie moves": g["tie_moves"].sum(),
        }
    )


def unproven_runs(folder: Path) -> dict[str, str]:
    """The runs of a results folder whose numbers rest on solver answers not proven optimal, each with why
    ("3 of 95 rounds ended unproven (time_limit 3)", "stopped with status time_limit (gap unknown)"), in
    the folder's run order.  Read from the files alone, like every report."""
    meta = results.read_meta(folder)
    found: dict[str, str] = {}
    path = folder / "rounds.csv.gz"
    if path.is_file():
        rounds = pd.read_csv(path, usecols=["run", "status"])
        for run, status in rounds.groupby("run", sort=False)["status"]:
            bad = status[status != "optimal"].value_counts()
            if len(bad):
                kinds = ", ".join(f"{s} {n}" for s, n in bad.items())
                found[str(run)] = f"{int(bad.sum())} of {len(status)} rounds ended unproven ({kinds})"
    for run, facts in meta.get("runs", {}).items():
        if facts.get("kind") == "oracle" and facts.get("status", "optimal") != "optimal":
            gap = facts.get("gap")
            found[run] = (
                f"stopped with status {facts['status']} "
                f"(gap {'unknown' if gap is None or gap != gap else f'{gap:.3g}'})"
            )
    order = meta.get("strategies", [])
    return dict(sorted(found.items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order)))


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


def report_markdown(folder: Path, name: str | None = None) -> str:
    meta = results.read_meta(folder)
    table = load_kpis(folder)
    unproven = unproven_runs(folder)
    sc = meta["scenario"]
    args = sc.get("args", {})
    lines = [f"# rpbench results: {sc['label']}", ""]
    if sc.get("synthetic"):
        lines += ["> **Synthetic scenario** — not real order data (see the scenario label).", ""]
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
    summary = solver_summary(folder)
    if summary is not None:
        lines += [
            "## Solver statistics per run",
            "",
            summary.to_markdown() if _has_tabulate() else "```\n" + summary.to_string() + "\n```",
            "",
        ]
    walls = {r: v.get("wall_s") for r, v in meta.get("runs", {}).items() if v.get("wall_s") is not None}
    if walls:
        lines += ["Wall time per run: " + ", ".join(f"{run_label(r, styles)} {w:.2f} s" for r, w in walls.items()), ""]
    if results.run_names(folder):
        verify = f"Verify this folder with `rpbench check {name or folder.name}`."
    else:
        verify = (
            "This is a published light copy without the event logs: `check.txt` holds the checker's verdict "
            "on the full folder; rerun the command above to regenerate and re-check it."
        )
    lines += [f"KPI definitions: see `rpbench/results/metrics.py` (and the README). {verify}", ""]
    return "\n".join(lines)


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


def write_report(folder: Path, name: str | None = None) -> Path:
    """Write ``report.md`` (and its PNG plots) into ``folder`` (``name``: its final name, for the text)."""
    text = report_markdown(folder, name)
    hourly_png = hourly_plot(folder)
    if hourly_png is not None:
        text += (
            "\n## Per hour\n\nKPIs by request hour (saving of a pair counted in the hour of its earlier "
            "request). The upper bound's line is its whole-period matching split the same way: per hour it "
            f"describes that matching and is not itself a bound.\n\n![per-hour comparison]({hourly_png.name})\n"
        )
    path = folder / "report.md"
    path.write_text(text)
    return path


def hourly_plot(folder: Path) -> Path | None:
    """``hourly.png`` when the folder covers more than two hours (full-day and trace scenarios)."""
    path = folder / "hourly.csv"
    if not path.is_file():
        return None
    hourly = pd.read_csv(path)
    if hourly.empty or hourly["hour"].nunique() <= 2:
        return None
    meta = results.read_meta(folder)
    return hourly_figure(hourly, folder / "hourly.png", meta["scenario"]["label"])


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
    known = KPI_ORDER + EXTRA_KPIS + list(RATIO_ROWS) + ["wall_s"]
    unknown = [m for m in metrics if m not in known]
    if unknown or not metrics:
        raise ResultsError(f"unknown metric {unknown[0] if unknown else '(none)'!r}; known metrics: {', '.join(known)}")
    return metrics


def selected_markdown(table: pd.DataFrame, styles: Styles | None = None) -> str:
    cols = list(table.columns)
    out = ["| Metric | " + " | ".join(run_label(c, styles) for c in cols) + " |", "|---|" + "---:|" * len(cols)]
    for k in table.index:
        out.append(f"| {KPI_LABELS.get(k, k)} | " + " | ".join(fmt(k, table.loc[k, c]) for c in cols) + " |")
    return "\n".join(out)
