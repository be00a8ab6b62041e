"""Reports rendered from result files alone (tables now; plots in rpbench.plots).

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

from . import paper, results
from .exceptions import ResultsError
from .metrics import KPI_LABELS, KPI_ORDER

RUN_LABELS = {"np": "NP", "mb": "MB", "rtv": "RTV", "fl": "FL", "fl-nd": "FL-no_delay", "oracle1": "Oracle-1",
              "oracle2": "Oracle-2"}
_DECIMALS = {"response_rate": 2, "pairing_ratio": 2, "competitive_ratio": 3, "pairing_ratio_of_orders": 2}


def fmt(kpi: str, value) -> str:
    """Format a KPI value the way the paper prints it ("/" for undefined)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "/"
    value = float(value) + 0.0        # no "-0"
    if kpi in _DECIMALS:
        return f"{value:.{_DECIMALS[kpi]}f}"
    if abs(value) >= 100 or kpi.endswith("_s") or kpi.endswith("_m"):
        text = f"{value:,.0f}"
    else:
        text = f"{value:.1f}"
    return "0" if text in ("-0", "-0.0") else text


def load_kpis(folder: Path) -> pd.DataFrame:
    """Wide KPI table (rows = KPI keys, columns = runs in meta.json's order)."""
    meta = results.read_meta(folder)
    tidy = results.read_csv(folder / "kpis.csv")
    missing = {"run", "kpi", "value"} - set(tidy.columns)
    if missing:
        raise ResultsError(f"{str(folder / 'kpis.csv')!r} lacks column(s) {', '.join(sorted(missing))}")
    wide = tidy.pivot(index="kpi", columns="run", values="value")
    order = [r for r in meta.get("strategies", []) if r in wide.columns] + \
            [r for r in wide.columns if r not in meta.get("strategies", [])]
    wide = wide[order]
    if "oracle1" in wide.columns and "total_saving_km" in wide.index:
        best = wide.loc["total_saving_km", "oracle1"]
        wide.loc["competitive_ratio"] = wide.loc["total_saving_km"] / best if best else np.nan
    return wide


def table_rows(table: pd.DataFrame) -> list[str]:
    rows = [k for k in KPI_ORDER if k in table.index]
    if "competitive_ratio" in table.index:
        rows.append("competitive_ratio")
    return rows


def text_table(table: pd.DataFrame, *, title: str | None = None) -> str:
    """A plain-text table for the terminal (KPIs as rows, runs as columns)."""
    rows = table_rows(table)
    cols = list(table.columns)
    head = ["Metric"] + [RUN_LABELS.get(c, c) for c in cols]
    body = [[KPI_LABELS.get(k, k)] + [fmt(k, table.loc[k, c]) for c in cols] for k in rows]
    widths = [max(len(r[i]) for r in [head] + body) for i in range(len(head))]
    lines = []
    if title:
        lines.append(title)
    lines.append("  ".join(h.ljust(widths[0]) if i == 0 else h.rjust(widths[i]) for i, h in enumerate(head)))
    lines.append("  ".join("-" * w for w in widths))
    for r in body:
        lines.append("  ".join(x.ljust(widths[0]) if i == 0 else x.rjust(widths[i]) for i, x in enumerate(r)))
    return "\n".join(lines)


def markdown_table(table: pd.DataFrame, paper_values: dict | None = None) -> str:
    """The Table 2 layout in markdown; with ``paper_values`` each cell reads "rpbench (paper)"."""
    rows = table_rows(table)
    cols = list(table.columns)
    out = ["| Metric | " + " | ".join(RUN_LABELS.get(c, c) for c in cols) + " |",
           "|---|" + "---:|" * len(cols)]
    for k in rows:
        cells = []
        for c in cols:
            cell = fmt(k, table.loc[k, c])
            if paper_values is not None:
                ref = paper_values.get(c, {}).get(k, float("nan")) if k != "competitive_ratio" else (
                    paper.FL_COMPETITIVE_RATIO if c == "fl" else float("nan"))
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
    return pd.DataFrame({
        "rounds": g.size(),
        "mean cols": g["cols"].mean().round(1),
        "max cols": g["cols"].max(),
        "strategy build p50 (ms)": (g["strategy_build_s"].median() * 1e3).round(3),
        "solve p50 (ms)": (g["solve_s"].median() * 1e3).round(3),
        "solve p95 (ms)": (g["solve_s"].quantile(0.95) * 1e3).round(3),
        "solver total (s)": (g["solver_build_s"].sum() + g["solve_s"].sum() + g["extract_s"].sum()).round(3),
        "not optimal": g["status"].apply(lambda s: int((s != "optimal").sum())),
        "tie moves": g["tie_moves"].sum(),
    })


def report_markdown(folder: Path, name: str | None = None) -> str:
    meta = results.read_meta(folder)
    table = load_kpis(folder)
    sc = meta["scenario"]
    args = sc.get("args", {})
    lines = [f"# rpbench results: {sc['label']}", ""]
    if sc.get("synthetic"):
        lines += ["> **Synthetic scenario** — not real order data (see the scenario label).", ""]
    lines += [f"- scenario `{sc['name']}`, seed {sc['seed']}, {sc['summary']['orders']} orders, "
              f"{sc['summary']['vehicles']} vehicles, {sc['summary']['nodes']} nodes",
              f"- solver preset `{meta['preset']['name']}` (backend `{meta['preset']['backend']}`)",
              f"- rpbench {meta['versions']['rpbench']}, commit `{meta.get('git_commit')}`, "
              f"written {meta.get('created')}", ""]
    if meta.get("command"):
        lines += ["Command:", "", f"    {meta['command']}", ""]
    lines += ["## Comparison (paper Table 2 layout)", "", markdown_table(table), ""]
    if paper.table2_applies(sc["name"], args.get("date"), args.get("sample")):
        lines += ["## Beside the paper", "",
                  "Each cell: rpbench (paper Table 2). The paper's numbers are shown for comparison only; "
                  "nothing is tuned to them.", "", markdown_table(table, paper.TABLE2), ""]
    summary = solver_summary(folder)
    if summary is not None:
        lines += ["## Solver statistics per run", "", summary.to_markdown() if _has_tabulate() else
                  "```\n" + summary.to_string() + "\n```", ""]
    walls = {r: v.get("wall_s") for r, v in meta.get("runs", {}).items() if v.get("wall_s") is not None}
    if walls:
        lines += ["Wall time per run: " + ", ".join(f"{RUN_LABELS.get(r, r)} {w:.2f} s" for r, w in walls.items()),
                  ""]
    lines += ["KPI definitions: see `rpbench/metrics.py` (and the README). Verify this folder with "
              f"`rpbench check {name or folder.name}`.", ""]
    return "\n".join(lines)


def _has_tabulate() -> bool:
    try:
        import tabulate  # noqa: F401
    except ImportError:
        return False
    return True


def write_report(folder: Path, name: str | None = None) -> Path:
    """Write ``report.md`` into ``folder`` (``name``: the folder's final name, for the text)."""
    path = folder / "report.md"
    path.write_text(report_markdown(folder, name))
    return path
