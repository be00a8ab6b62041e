"""``report.html`` of every kind of results folder, rendered from its files alone (:func:`write_html`).

A comparison page carries the comparison table (each cell holding its raw value), the interactive
figures of report.md, the map (:mod:`rpbench.report.html.mapdata`) and the solver statistics.  The
pages of parent folders (multi-day, sweep) and of ``rpbench replicate`` folders show their report.md,
with interactive figures in place of its PNGs and links to their children's pages.
"""

from __future__ import annotations

import html
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench import files, results
from rpbench.data import paper
from rpbench.report.comparison import (
    UNPROVEN_MARK,
    bracket_lines,
    fmt,
    kpi_labels,
    offline_notes,
    solver_summary,
    table_rows,
    timeline_of,
    unproven_notes,
    wall_lines,
)
from rpbench.report.evaluation import LEADERBOARD_PNG, board_metrics, read_leaderboard
from rpbench.report.html import figures
from rpbench.report.html.mapdata import map_payload
from rpbench.report.html.page import Cell, Page
from rpbench.results import layout
from rpbench.results.layout import REPORT_HTML
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.read import load_kpis, unproven_runs
from rpbench.results.runs import run_label, run_styles


def write_html(folder: Path, name: str | None = None, dest: Path | None = None, *, published: bool = False) -> Path:
    """Write ``report.html`` of ``folder`` into it, or into ``dest`` (``folder`` is then only read).

    ``name``: the folder's final name, for the text; ``published``: the page goes into a published light
    copy (rendered here from the full folder, so it keeps the map the copy's files could not draw).
    """
    dest = folder if dest is None else dest
    kind = results.read_meta(folder).get("kind", "comparison")
    if kind == "multi-day":
        page = multiday_page(folder, name)
    elif kind == "sweep":
        page = sweep_page(folder, name)
    elif kind == "evaluate":
        page = evaluation_page(folder, name)
    elif kind == "replication":
        page = markdown_page(folder, "rpbench replicate", name, children=_subfolders(folder))
    else:
        page = comparison_page(folder, name, published=published)
    path = dest / REPORT_HTML
    tmp = path.with_name(f".{REPORT_HTML}.partial")
    files.write_text(tmp, page.render())  # non-UTF-8 bytes of a quoted path or command line escaped
    tmp.replace(path)
    return path


# ---- comparison folders -------------------------------------------------------------------------------


def comparison_page(folder: Path, name: str | None = None, *, published: bool = False) -> Page:
    meta = results.read_meta(folder)
    sc = meta["scenario"]
    table = load_kpis(folder)
    styles = run_styles(meta)
    unproven = unproven_runs(folder)
    page = Page(f"rpbench: {sc['label']}")
    page.heading(f"rpbench results: {sc['label']}", 1)
    _synthetic_banner(page, sc)
    summary = sc.get("summary", {})
    page.bullets(
        [
            f"scenario {sc['name']}, seed {sc.get('seed')}, {summary.get('orders')} orders, "
            f"{summary.get('vehicles')} vehicles, {summary.get('nodes')} nodes",
            f"solver preset {meta['preset']['name']} (backend {meta['preset']['backend']})",
            f"rpbench {meta['versions']['rpbench']}, commit {meta.get('git_commit')}, written {meta.get('created')}",
        ]
    )
    if meta.get("command"):
        page.paragraph("Command:")
        page.code(meta["command"])
    page.markup(
        '<nav class="toc"><a href="#comparison">Comparison</a><a href="#figures">Figures</a>'
        '<a href="#map">Map</a><a href="#solver">Solver statistics</a></nav>'
    )
    page.heading("Comparison (paper Table 2 layout)", 2, "comparison")
    _comparison_table(page, table, unproven, styles)
    for line in bracket_lines(table, meta, styles) + unproven_notes(unproven, styles) + offline_notes(table, meta):
        if line:
            page.paragraph(_plain(line), "muted")
    if paper.table2_applies(sc["name"], sc.get("args", {}).get("date"), sc.get("args", {}).get("sample")):
        page.heading("Beside the paper", 3)
        page.paragraph("Each cell: rpbench (paper Table 2). The paper's numbers are shown for comparison only.")
        _paper_table(page, table, styles)
    page.heading("Figures", 2, "figures")
    page.figure(
        "fig-kpis",
        figures.kpi_bars(table, fmt, styles),
        "Headline KPIs, one bar per run (hover for the value; click a legend entry to hide or show a run in "
        "every panel). Offline runs have no response rate nor pick-up time. The competitive ratio of each "
        "simulated run is an interval: the bar reaches saving / upper bound, the error bar saving / best known "
        "schedule.",
    )
    timeline = timeline_of(folder)
    if isinstance(timeline, str):
        page.paragraph(timeline, "muted")
    else:
        page.figure(
            "fig-timeline",
            figures.timeline(
                timeline.table,
                hours=timeline.hours,
                start=timeline.start,
                bin_s=timeline.bin_s,
                horizon_s=timeline.horizon_s,
                styles=styles,
            ),
            f"Passengers waiting, being served and riding pooled ({timeline.bin_s / 60:g}-minute means) and "
            "cancelled so far, per strategy, from the event logs; the dotted line is where requests stop.",
        )
    hourly_path = folder / layout.HOURLY
    if hourly_path.is_file() and meta["scenario"].get("horizon_s", 0) > 2 * 3600:
        page.figure(
            "fig-hourly",
            figures.hourly_panels(results.read_csv(hourly_path), styles),
            "KPIs by request hour (a pair's saving counted in the hour of its earlier request); the upper "
            "bound's line splits its whole-period matching the same way and is not itself a bound per hour.",
        )
    page.heading("Map", 2, "map")
    payload = map_payload(folder)
    if isinstance(payload, str):
        page.paragraph(payload, "muted")
    else:
        _map_section(page, payload)
    page.heading("Solver statistics per run", 2, "solver")
    stats = solver_summary(folder)
    if stats is not None:
        page.table(
            ["run", *stats.columns],
            (
                [run_label(str(r), styles)] + [Cell(_number(v), numeric=True) for v in row]
                for r, row in zip(stats.index, stats.itertuples(index=False), strict=True)
            ),
        )
        rounds = pd.read_csv(folder / layout.ROUNDS, usecols=["run", "t_s", "cols", "solve_s", "status"])
        many = int(rounds.groupby("run").size().max()) > figures.MAX_ROUND_POINTS if len(rounds) else False
        caption = (
            f"Solve time of the batch rounds: median and maximum per {figures.ROUND_BIN_S / 60:g} minutes "
            f"(more than {figures.MAX_ROUND_POINTS:,} rounds per run)."
            if many
            else "Solve time of every batch round (hover: model columns and status)."
        )
        page.figure("fig-rounds", figures.round_times(rounds, styles), caption)
    else:
        page.paragraph("No per-round solver statistics in this folder.", "muted")
    for line in wall_lines(meta, styles):
        if line:
            page.paragraph(line, "muted")
    if published or not results.run_names(folder):
        verify = (
            "This is a published light copy without the event logs: check.txt holds the checker's verdict on "
            "the full folder; rerun the command above to regenerate and re-check it."
        )
    else:
        verify = f"Verify this folder with: rpbench check PATH, PATH being the path to {name or folder.name}."
    page.paragraph(f"KPI definitions: rpbench/results/metrics.py and the README. {verify}", "muted")
    return page


def _comparison_table(page: Page, table: pd.DataFrame, unproven: dict[str, str], styles) -> None:
    runs = [str(c) for c in table.columns]
    head = ["Metric"] + [run_label(r, styles) + (UNPROVEN_MARK if r in unproven else "") for r in runs]
    rows = []
    labels = kpi_labels(runs, styles)
    for kpi in table_rows(table):
        row: list[Cell | str] = [Cell(labels.get(kpi, kpi), {"kpi": kpi})]
        for r in runs:
            value = table.loc[kpi, r]
            raw = "" if pd.isna(value) else repr(float(value))
            row.append(Cell(fmt(kpi, value), {"run": r, "kpi": kpi, "value": raw}, numeric=True))
        rows.append(row)
    page.table(head, rows, ident="comparison-table")


def _paper_table(page: Page, table: pd.DataFrame, styles) -> None:
    runs = [str(c) for c in table.columns]
    rows = []
    for kpi in table_rows(table):
        row: list[Cell | str] = [KPI_LABELS.get(kpi, kpi)]
        for r in runs:
            ref = paper.TABLE2.get(r, {}).get(kpi, float("nan"))
            row.append(Cell(f"{fmt(kpi, table.loc[kpi, r])} ({fmt(kpi, ref)})", numeric=True))
        rows.append(row)
    page.table(["Metric"] + [run_label(r, styles) for r in runs], rows)


def _map_section(page: Page, payload: dict) -> None:
    page.map = payload
    options = "".join(
        f'<option value="{i}"{" selected" if i == payload["first_run"] else ""}>{html.escape(run["label"])}</option>'
        for i, run in enumerate(payload["runs"])
    )
    boxes = [("roads", "road network", True), ("pooled", "pooled pairs", True), ("solo", "solo trips", False)]
    boxes += [("cancelled", "cancelled requests", True), ("density", "density", False)]
    checks = "".join(
        f'<label><input type="checkbox" id="map-show-{k}"{" checked" if on else ""}> {html.escape(text)}</label>'
        for k, text, on in boxes
    )
    window_min = payload["period"]["window_s"] / 60
    page.markup(
        '<div class="controls">'
        f'<label>strategy <select id="map-run">{options}</select></label>{checks}</div>'
        '<div class="controls"><label>time window '
        f'<input type="range" id="map-window" min="0" max="1" step="1" value="{payload["first_window"]}"></label>'
        '<button type="button" id="map-play">Play</button>'
        f'<span class="muted">0 = the whole period; then {window_min:g}-minute windows</span></div>'
        '<p id="map-note" class="muted"></p>'
        '<figure><div class="plot" id="map-plot"></div><figcaption>'
        "The road network from its own node coordinates (no map tiles). A pooled pair is drawn through its "
        "four stops in the order served: first pick-up (dot), join (the second pick-up, diamond), drop-offs "
        "(crosses); a solo trip from pick-up to drop-off; a cancelled request at its origin. Lines join the "
        "stops straight, not along the roads driven. An item falls in the window of its first pick-up (or "
        f"cancellation). A window with more than {payload['max_drawn']:,} items of a layer draws one in k "
        "(said above the map); the density layer counts them all.</figcaption></figure>"
    )
    if payload["offline"]:
        page.paragraph(
            f"The offline runs ({', '.join(payload['offline'])}) pair orders after the fact and have no event "
            "log: they are not on the map.",
            "muted",
        )


# ---- parent and replication folders ------------------------------------------------------------------


def multiday_page(parent: Path, name: str | None = None) -> Page:
    from rpbench.report.plots import MULTIDAY_PLOT_KPIS
    from rpbench.results.parents import by_day_table, day_folders

    days = day_folders(parent)
    styles = run_styles(results.read_meta(days[0])) if days else {}
    page = markdown_page(parent, "rpbench multi-day results", name, children=days, drop_images=True)
    table = by_day_table(parent)
    page.heading("Per-day KPIs (interactive)", 2)
    page.figure(
        "fig-by-day",
        figures.by_parameter(table, "date", MULTIDAY_PLOT_KPIS, "date", styles, dates=True),
        "Choose the KPI in the menu; click a legend entry to hide or show a run.",
    )
    return page


def sweep_page(parent: Path, name: str | None = None) -> Page:
    from rpbench.results.parents import sweep_table

    meta = results.read_meta(parent)
    points = [parent / p["label"] for p in meta["points"]]
    styles = run_styles(results.read_meta(points[0])) if points else {}
    page = markdown_page(parent, f"rpbench sweep {meta['sweep']}", name, children=points, drop_images=True)
    table = sweep_table(parent)
    page.heading("The sweep (interactive)", 2)
    page.figure(
        "fig-sweep",
        figures.sweep_panels(table[table["run"].isin(meta["strategies"])], meta["parameter"], meta["kpis"], styles),
        "One panel per KPI; click a legend entry to hide or show a run in every panel.",
    )
    return page


def evaluation_page(folder: Path, name: str | None = None) -> Page:
    """An evaluation's report.md with its figures drawn in place, interactive: the leaderboard (a metric menu)
    and the ranking metric per day (each run's mean over the day's seeds, their range as error bars)."""
    from rpbench.report.evaluation import by_day_png, evaluation_runs, unit_records

    meta = results.read_meta(folder)
    protocol = meta["protocol"]
    children = [folder / c for c in meta.get("children", [])]
    styles = run_styles(results.read_meta(children[0])) if children else {}
    board = read_leaderboard(folder)
    metrics = board_metrics(list(protocol["metrics"]))
    slots = {
        LEADERBOARD_PNG: (
            "fig-leaderboard",
            figures.leaderboard_bars(board, metrics, styles),
            "Each strategy's mean over the (day, seed) runs with its bootstrap interval; choose the metric in the "
            "menu.",
        )
    }
    units_path = folder / layout.UNITS
    if units_path.is_file():
        units = results.read_csv(units_path)
        units["day"] = units["day"].astype(object).fillna("").astype(str)  # undated units have no day
        runs = evaluation_runs(protocol["strategies"], unit_records(folder))
        by_day = figures.seeds_by_day(units, metrics, runs, styles)
        if by_day is not None:
            slots[by_day_png(protocol["metrics"][0])] = (
                "fig-by-day",
                by_day,
                "Each strategy's mean over the seeds of each day, the seeds' range as an error bar; choose the "
                "metric in the menu; click a legend entry to hide or show a run.",
            )
    return markdown_page(folder, "rpbench evaluation", name, children=children, interactive=slots)


#: A figure's place in a report.md rendered to HTML, until the page puts the figure there.
_SLOT = "RPBENCHFIGURESLOT{}"


def markdown_page(
    folder: Path,
    title: str,
    name: str | None = None,
    *,
    children: Sequence[Path] = (),
    drop_images: bool = False,
    interactive: Mapping[str, tuple[str, Any, str]] | None = None,
) -> Page:
    """A page showing ``folder``'s report.md with links to the pages of ``children``; ``name``: the folder's
    final name (it may be written under a temporary one).  ``interactive``: an image of report.md (its file
    name) -> the interactive figure drawn in its place (slot id, Plotly figure, caption); the other PNGs are left
    out with ``drop_images`` (the page draws its own), else named (a PNG is a separate file: the page,
    copied alone, would show a broken image).  Wide tables scroll in their own box."""
    from markdown_it import MarkdownIt

    text = (folder / layout.REPORT).read_text(encoding="utf-8") if (folder / layout.REPORT).is_file() else ""
    interactive = interactive or {}
    placed: list[str] = []

    def own_line(found: re.Match) -> str:
        if found.group(2) in interactive and found.group(2) not in placed:
            placed.append(found.group(2))
            return _SLOT.format(len(placed) - 1)
        return "" if drop_images else found.group(0)

    text = re.sub(r"^!\[([^\]]*)\]\(([^)]*)\)[ \t]*$", own_line, text, flags=re.MULTILINE)
    if not drop_images:  # a PNG is a separate file: the page, copied alone, names it, never shows it broken
        text = re.sub(r"!\[([^\]]*)\]\(([^)]*)\)", r"(figure `\2` beside report.md: \1)", text)
    page = Page(f"{title}: {name or folder.name}")
    body = MarkdownIt("commonmark", {"html": False}).enable("table").render(text)
    body = body.replace("<table>", '<div class="scroll"><table>').replace("</table>", "</table></div>")
    parts = re.split(r"<p>" + _SLOT.format(r"(\d+)") + r"</p>", body)
    page.markup(parts[0] or f"<h1>{html.escape(title)}</h1>")
    for k, after in zip(parts[1::2], parts[2::2], strict=True):
        page.figure(*interactive[placed[int(k)]])
        if after:
            page.markup(after)
    unplaced = [f for f in interactive if f not in placed]  # a report.md that does not embed them (older)
    if unplaced:
        page.heading("Figures (interactive)", 2)
        for f in unplaced:
            page.figure(*interactive[f])
    if children:
        links = "".join(  # a published evaluation's units have a report.md but no page
            f'<li><a href="{html.escape(c.name)}/{REPORT_HTML if (c / REPORT_HTML).is_file() else layout.REPORT}">'
            f"{html.escape(c.name)}</a></li>"
            for c in children
            if (c / layout.META).is_file()
        )
        page.heading("Folders inside", 2)
        page.markup(f'<ul class="children">{links}</ul>')
    return page


def _subfolders(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_dir() and (p / layout.META).is_file())


# ---- text --------------------------------------------------------------------------------------------


def _synthetic_banner(page: Page, scenario: dict) -> None:
    from rpbench.report.comparison import synthetic_lines

    for line in synthetic_lines(scenario):
        if line.startswith("> "):
            page.markup(f'<p class="banner">{_inline(line[2:])}</p>')


def _plain(markdown_line: str) -> str:
    """A one-line report note as plain text (emphasis and code marks dropped)."""
    return re.sub(r"\\?\*\*|`", "", markdown_line).replace("\\*", "*")


def _inline(markdown_line: str) -> str:
    """A one-line note as HTML (bold and code kept)."""
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).renderInline(markdown_line)


def _number(value) -> str:
    if isinstance(value, float):
        return f"{value:,.3f}".rstrip("0").rstrip(".") if value == value else "/"
    return f"{value:,}" if isinstance(value, int) else str(value)
