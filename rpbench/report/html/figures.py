"""Interactive (Plotly) versions of the report's figures, each a pure function of tables read from result files.

They mirror :mod:`rpbench.report.plots` panel for panel; every trace of a run shares the run's legend
group, so a click on a legend entry hides or shows that run in every panel.
"""

from __future__ import annotations

import html
import math
import textwrap
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from rpbench.report.plots import (
    HOURLY_PANELS,
    INTERVAL_MARKS,
    KPI_PANELS,
    RATIO_ENDS,
    RATIO_INTERVAL,
    TIMELINE_PANELS,
    axis_label,
    interval_ends,
    interval_metrics,
    interval_rows,
    parameter_label,
    run_colors,
)
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.runs import Styles, run_label

FONT = {"family": "system-ui, -apple-system, Segoe UI, Roboto, Helvetica Neue, Arial, sans-serif", "size": 12}


def plotly_text(text: str) -> str:
    """A label as Plotly text, which reads a few HTML tags and entities: shown as written, never as markup."""
    return html.escape(text, quote=False)


def css_colors(runs: Sequence[str], styles: Styles | None = None) -> dict[str, str]:
    """Each run's colour (the report's matplotlib colour, as the hex code a browser reads)."""
    from matplotlib.colors import to_hex

    return {r: to_hex(c) for r, c in run_colors(list(runs), styles).items()}


def _layout(fig: Any, title: str | None, height: int) -> Any:
    fig.update_layout(
        title={"text": title, "x": 0.01} if title else None,
        height=height,
        font=FONT,
        template="plotly_white",
        margin={"l": 60, "r": 20, "t": 70 if title else 40, "b": 50},
        legend={"orientation": "h", "y": -0.12, "x": 0},
        hovermode="closest",
    )
    return fig


def _subplots(rows: int, cols: int, titles: Sequence[str], **kw: Any) -> Any:
    from plotly.subplots import make_subplots

    return make_subplots(rows=rows, cols=cols, subplot_titles=list(titles), **kw)


#: The competitive ratio's panel in the page: what its marks are (the PNG's title names them for matplotlib).
RATIO_PANEL_TITLE = "Competitive ratio<br>bar: saving / U; ◆: saving / LB"
#: Tick labels of the bar panels: this size, wrapped at this many characters, turned by this angle; the rows
#: of panels are set apart by the height the turned labels take (:func:`tick_extent_px`), so that a row's
#: labels never reach the titles of the row below.
TICK_FONT_PX, TICK_WRAP, TICK_ANGLE = 11, 13, -45
BAR_TEXT_PX = 10
PANEL_PX = 250


def tick_text(label: str) -> str:
    """A run's label as a tick label: escaped, wrapped onto lines of at most :data:`TICK_WRAP` characters."""
    return "<br>".join(plotly_text(line) for line in textwrap.wrap(label, TICK_WRAP, break_long_words=False))


def tick_extent_px(labels: Sequence[str], angle: float = TICK_ANGLE, font_px: float = TICK_FONT_PX) -> float:
    """A generous estimate of the height below an axis that its tick labels (``<br>``-separated lines)
    take when turned by ``angle`` degrees: the longest line's run up, plus the lines' stacked height."""
    lines = [line for label in labels for line in html.unescape(label).split("<br>")] or [""]
    longest = max(len(line) for line in lines) * 0.62 * font_px
    rows = max(label.count("<br>") + 1 for label in labels) if labels else 1
    turn = math.radians(abs(angle))
    return longest * math.sin(turn) + rows * 1.25 * font_px * math.cos(turn) + 8


def kpi_bars(table: pd.DataFrame, text: Callable[[str, float], str], styles: Styles | None = None) -> Any:
    """The headline KPIs (:data:`~rpbench.report.plots.KPI_PANELS`), one bar per run with its value; the
    competitive ratio as its interval: a bar up to saving / U, a line from it up to a diamond at saving / LB."""
    import plotly.graph_objects as go

    ends = interval_ends(table)
    panels = [
        (k, RATIO_PANEL_TITLE if k == RATIO_INTERVAL else name)
        for k, name in KPI_PANELS
        if (bool(ends[0]) if k == RATIO_INTERVAL else k in table.index and table.loc[k].notna().any())
    ]
    runs = [str(r) for r in table.columns]
    colors = css_colors(runs, styles)
    labels = {r: plotly_text(run_label(r, styles)) for r in runs}
    ticks = {r: tick_text(run_label(r, styles)) for r in runs}
    cols = 3
    rows = max(1, -(-len(panels) // cols))
    below = tick_extent_px(list(ticks.values()))
    title_px = 18 * max(name.count("<br>") + 1 for _, name in panels) if panels else 18
    gap = below + title_px + 20  # px between rows: the turned tick labels, then the next row's titles
    legend_px = 60
    top, bottom = title_px + 20, below + legend_px
    area = rows * PANEL_PX + (rows - 1) * gap
    fig = _subplots(rows, cols, [name for _, name in panels], vertical_spacing=gap / area if rows > 1 else 0.1,
                    horizontal_spacing=0.08)  # fmt: skip
    shown: set[str] = set()
    for i, (kpi, _) in enumerate(panels):
        r, c = divmod(i, cols)
        name = plotly_text(KPI_LABELS.get(kpi, kpi))
        for run in runs:
            traces = _ratio_traces(run, ends, text) if kpi == RATIO_INTERVAL else _kpi_bar(table, kpi, run, text)
            for kind, trace in traces:
                hover = trace.pop("hover", "%{text}")
                if kind == "bar":
                    trace["marker_color"] = colors[run]
                fig.add_trace(
                    (go.Bar if kind == "bar" else go.Scatter)(
                        x=[labels[run]],
                        name=labels[run],
                        legendgroup=run,
                        showlegend=run not in shown,
                        hovertemplate=f"{labels[run]}<br>{name}: {hover}<extra></extra>",
                        **trace,
                    ),
                    row=r + 1,
                    col=c + 1,
                )
                shown.add(run)
        if kpi == RATIO_INTERVAL:
            top_value = float(np.nanmax(np.concatenate([ends[1], ends[2], [0.0]])))
            fig.update_yaxes(range=[0, 1.35 * (top_value or 1.0)], row=r + 1, col=c + 1)  # room for the values
        fig.update_yaxes(title_text=axis_label(kpi), rangemode="tozero", row=r + 1, col=c + 1)
    fig.update_xaxes(tickangle=TICK_ANGLE, tickfont={"size": TICK_FONT_PX}, tickvals=[labels[r] for r in runs],
                     ticktext=[ticks[r] for r in runs])  # fmt: skip
    fig.update_layout(uniformtext={"minsize": BAR_TEXT_PX, "mode": "show"}, bargap=0.25)
    _layout(fig, None, round(top + area + bottom))
    fig.update_layout(
        margin={"t": round(top), "b": round(bottom)},
        legend={"y": -below / area, "yanchor": "top"},  # below the last row's tick labels
    )
    return fig


def _kpi_bar(table: pd.DataFrame, kpi: str, run: str, text: Callable[[str, float], str]) -> list[tuple[str, dict]]:
    """A run's bar with its value written above (kind, trace properties); none without a value."""
    value = table.loc[kpi, run]
    if pd.isna(value):
        return []
    bar = {"y": [float(value)], "text": [text(kpi, float(value))], "textposition": "outside", "cliponaxis": False}
    return [("bar", {**bar, "textfont": {"size": BAR_TEXT_PX + 1}})]


def _ratio_traces(
    run: str, ends: tuple[list[str], np.ndarray, np.ndarray], text: Callable[[str, float], str]
) -> list[tuple[str, dict]]:
    """A run's competitive ratio: the bar up to saving / U (none without a bound), a black diamond at
    saving / LB joined to the bar's top by a line, both ends written above the diamond (saving / LB first)."""
    runs, low, high = ends
    if run not in runs:
        return []
    k = runs.index(run)
    lo, hi = float(low[k]), float(high[k])
    shown = [text(RATIO_ENDS[0], lo) if not np.isnan(lo) else "/", text(RATIO_ENDS[1], hi) if not np.isnan(hi) else "/"]
    both = f"[{shown[0]}, {shown[1]}]"
    out = []
    if not np.isnan(lo):
        out.append(("bar", {"y": [lo], "text": [both], "textposition": "none"}))
    if not np.isnan(hi):
        base = 0.0 if np.isnan(lo) else lo
        out.append(
            (
                "scatter",
                {
                    "y": [hi],
                    "text": [f"{shown[1]}<br>{shown[0]}"],
                    "customdata": [both],
                    "mode": "markers+text",
                    "textposition": "top center",
                    "textfont": {"size": BAR_TEXT_PX},
                    "marker": {"symbol": "diamond", "color": "black", "size": 8},
                    "error_y": {
                        "type": "data",
                        "symmetric": False,
                        "array": [0.0],
                        "arrayminus": [hi - base],
                        "width": 0,
                        "thickness": 1.2,
                        "color": "black",
                    },
                    "cliponaxis": False,
                    "hover": "%{customdata}",
                },
            )
        )
    return out


def timeline(
    table: pd.DataFrame, *, hours: bool, start: str | None, bin_s: float, horizon_s: float, styles: Styles | None = None
) -> Any:
    """The period's timeline: waiting, being served, riding pooled, cancelled so far; one line per run."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in table["run"]))
    colors = css_colors(runs, styles)
    scale = 3600.0 if hours else 60.0
    fig = _subplots(2, 2, [name for _, name in TIMELINE_PANELS], shared_xaxes=True, vertical_spacing=0.1)
    shown: set[str] = set()
    for i, (state, _) in enumerate(TIMELINE_PANELS):
        r, c = divmod(i, 2)
        sel = table[table["state"] == state]
        for run, g in sel.groupby("run", sort=False):
            run = str(run)
            label = plotly_text(run_label(run, styles))
            fig.add_trace(
                go.Scatter(
                    x=(g["t_s"] / scale).round(4).to_numpy(),
                    y=g["value"].round(3).to_numpy(),
                    mode="lines",
                    name=label,
                    legendgroup=run,
                    showlegend=run not in shown,
                    line={"color": colors[run], "width": 1.6},
                    hovertemplate=f"{label}: %{{y:.1f}}<extra></extra>",
                ),
                row=r + 1,
                col=c + 1,
            )
            shown.add(run)
        fig.add_vline(x=horizon_s / scale, line_dash="dot", line_color="grey", row=r + 1, col=c + 1)
        width = f"{bin_s / 60:g}-min"
        fig.update_yaxes(
            title_text="passengers (total)" if state == "cancelled" else f"passengers ({width} mean)",
            rangemode="tozero",
            row=r + 1,
            col=c + 1,
        )
    since = f" ({start})" if start else ""
    for c in (1, 2):
        fig.update_xaxes(title_text=f"{'hours' if hours else 'minutes'} since the scenario start{since}", row=2, col=c)
    fig.update_layout(hovermode="x unified")
    return _layout(fig, None, 640)


def hourly_panels(table: pd.DataFrame, styles: Styles | None = None) -> Any:
    """The per-hour KPIs (``hourly.csv``): four panels, one line per run."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in table["run"]))
    colors = css_colors(runs, styles)
    fig = _subplots(2, 2, [name for _, name in HOURLY_PANELS], shared_xaxes=True, vertical_spacing=0.1)
    shown: set[str] = set()
    for i, (col, _) in enumerate(HOURLY_PANELS):
        r, c = divmod(i, 2)
        for run, g in table.groupby("run", sort=False):
            run = str(run)
            if not g[col].notna().any():
                continue
            label = plotly_text(run_label(run, styles))
            fig.add_trace(
                go.Scatter(
                    x=g["hour"].to_numpy(),
                    y=g[col].to_numpy(dtype=float),
                    mode="lines+markers",
                    name=label,
                    legendgroup=run,
                    showlegend=run not in shown,
                    line={"color": colors[run]},
                    marker={"size": 4},
                    hovertemplate=f"{label}, hour %{{x}}: %{{y:.3~f}}<extra></extra>",
                ),
                row=r + 1,
                col=c + 1,
            )
            shown.add(run)
        fig.update_yaxes(title_text=axis_label(col), row=r + 1, col=c + 1)
    for c in (1, 2):
        fig.update_xaxes(title_text="hour of day (request time)", row=2, col=c)
    return _layout(fig, None, 620)


#: Above this many rounds per run (a full day has 8,640), the solve times are drawn per 10-minute bin
#: (median and maximum) instead of one point per round.
MAX_ROUND_POINTS = 2000
ROUND_BIN_S = 600.0


def round_times(rounds: pd.DataFrame, styles: Styles | None = None) -> Any:
    """Every batch round's solve time against the time of the round, one series per run (log scale); for
    long scenarios (:data:`MAX_ROUND_POINTS`) the median and maximum per :data:`ROUND_BIN_S` bin."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in rounds["run"]))
    colors = css_colors(runs, styles)
    long = float(rounds["t_s"].max()) > 2 * 3600.0 if len(rounds) else False
    scale, unit = (3600.0, "hours") if long else (60.0, "minutes")
    binned = bool(len(rounds)) and int(rounds.groupby("run").size().max()) > MAX_ROUND_POINTS
    fig = go.Figure()
    for run, g in rounds.groupby("run", sort=False):
        run = str(run)
        label = plotly_text(run_label(run, styles))
        ms = np.maximum(g["solve_s"].to_numpy(dtype=float), 1e-7) * 1e3
        if binned:
            bins = pd.Series(ms).groupby((g["t_s"].to_numpy() // ROUND_BIN_S) * ROUND_BIN_S)
            mid = (bins.median().index.to_numpy() + ROUND_BIN_S / 2) / scale
            for stat, values, dash in (("median", bins.median(), None), ("max", bins.max(), "dot")):
                fig.add_trace(
                    go.Scatter(
                        x=mid.round(4),
                        y=values.to_numpy().round(4),
                        mode="lines",
                        name=f"{label} ({stat})",
                        legendgroup=run,
                        line={"color": colors[run], "dash": dash, "width": 1.4},
                        hovertemplate=f"{label}, {stat} per {ROUND_BIN_S / 60:g} min: %{{y:.3f}} ms<extra></extra>",
                    )
                )
            continue
        fig.add_trace(
            go.Scatter(
                x=(g["t_s"] / scale).round(4).to_numpy(),
                y=ms.round(4),
                customdata=np.stack([g["cols"].to_numpy(), g["status"].astype(str).to_numpy()], axis=1),
                mode="markers",
                name=label,
                legendgroup=run,
                marker={"color": colors[run], "size": 4, "opacity": 0.7},
                hovertemplate=f"{label}<br>solve %{{y:.3f}} ms<br>%{{customdata[0]}} columns, "
                "%{customdata[1]}<extra></extra>",
            )
        )
    fig.update_xaxes(title_text=f"{unit} since the scenario start")
    fig.update_yaxes(title_text="solve time per round (ms)", type="log")
    return _layout(fig, None, 420)


def by_parameter(
    table: pd.DataFrame, x: str, kpis: Sequence[str], x_title: str, styles: Styles | None = None, *, dates: bool = False
) -> Any:
    """A KPI chosen from a menu against days or a swept parameter (``table`` columns ``x``, run, kpi, value);
    :data:`~rpbench.report.plots.RATIO_INTERVAL` draws the competitive ratio as its interval (markers at
    saving / U, error bars up to saving / LB)."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in table["run"]))
    colors = css_colors(runs, styles)
    fig = go.Figure()
    owner: list[str] = []
    series = {k: _series(table, x, k) for k in kpis}
    kpis = [k for k in kpis if not series[k].empty]
    for k in kpis:
        for run, g in series[k].groupby("run", sort=False):
            run = str(run)
            label = plotly_text(run_label(run, styles))
            low = g["low"].to_numpy(dtype=float)
            high = g["high"].to_numpy(dtype=float)
            interval = {
                "error_y": {
                    "type": "data",
                    "symmetric": False,
                    "array": np.nan_to_num(high - low),
                    "arrayminus": 0 * low,
                },
                "customdata": high,
                "hovertemplate": f"{label}, %{{x}}: [%{{y:.4~g}}, %{{customdata:.4~g}}]<extra></extra>",
            }
            fig.add_trace(
                go.Scatter(
                    x=g[x].astype(str).to_numpy() if dates else g[x].to_numpy(dtype=float),
                    y=low,
                    mode="lines+markers",
                    name=label,
                    legendgroup=run,
                    visible=k == kpis[0],
                    line={"color": colors[run]},
                    marker={"size": 5},
                    **(
                        interval
                        if k == RATIO_INTERVAL
                        else {"hovertemplate": f"{label}, %{{x}}: %{{y:.4~g}}<extra></extra>"}
                    ),
                )
            )
            owner.append(k)
    _kpi_menu(fig, kpis, owner)
    fig.update_xaxes(title_text=x_title, type="category" if dates else None)
    return _layout(fig, None, 460)


def _series(table: pd.DataFrame, x: str, kpi: str) -> pd.DataFrame:
    """The points of one menu entry: ``x``, run, ``low`` (the value; the interval's lower end) and ``high``
    (the interval's upper end, the value itself for a KPI).  An interval without a bound starts at 0."""
    if kpi != RATIO_INTERVAL:
        sel = table[(table["kpi"] == kpi) & table["value"].notna()]
        return pd.DataFrame({x: sel[x], "run": sel["run"], "low": sel["value"], "high": sel["value"]})
    rows = interval_rows(table, x)
    return rows.assign(low=rows["low"].fillna(0.0), high=rows["high"].fillna(rows["low"]))


def _kpi_menu(fig: Any, kpis: Sequence[str], owner: Sequence[str]) -> None:
    """A menu choosing which KPI the figure shows: ``owner[i]`` is the KPI of trace i (the first KPI shown)."""
    buttons = [
        {
            "label": KPI_LABELS.get(k, k),
            "method": "update",
            "args": [{"visible": [o == k for o in owner]}, {"yaxis.title.text": axis_label(k)}],
        }
        for k in kpis
    ]
    menu = {"buttons": buttons, "x": 0, "y": 1.18, "xanchor": "left", "yanchor": "top", "showactive": True}
    fig.update_layout(updatemenus=[menu])
    fig.update_yaxes(title_text=axis_label(kpis[0]) if kpis else "")


def sweep_panels(table: pd.DataFrame, parameter: str, kpis: Sequence[str], styles: Styles | None = None) -> Any:
    """The sweep's KPIs against the swept parameter, one panel per KPI."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in table["run"]))
    colors = css_colors(runs, styles)
    cols = min(3, max(1, len(kpis)))
    rows = -(-len(kpis) // cols)
    fig = _subplots(rows, cols, [KPI_LABELS.get(k, k).split(" (")[0] for k in kpis], vertical_spacing=0.18)
    shown: set[str] = set()
    for i, k in enumerate(kpis):
        r, c = divmod(i, cols)
        sel = table[(table["kpi"] == k) & table["value"].notna()]
        for run, g in sel.groupby("run", sort=False):
            run = str(run)
            label = plotly_text(run_label(run, styles))
            fig.add_trace(
                go.Scatter(
                    x=g["point"].to_numpy(dtype=float),
                    y=g["value"].to_numpy(dtype=float),
                    mode="lines+markers",
                    name=label,
                    legendgroup=run,
                    showlegend=run not in shown,
                    line={"color": colors[run]},
                    hovertemplate=f"{label}, %{{x}}: %{{y:.4~g}}<extra></extra>",
                ),
                row=r + 1,
                col=c + 1,
            )
            shown.add(run)
        fig.update_xaxes(title_text=parameter_label(parameter), row=r + 1, col=c + 1)
        fig.update_yaxes(title_text=axis_label(k), row=r + 1, col=c + 1)
    return _layout(fig, None, 330 * rows + 90)


def profile_lines(profile: dict[str, tuple[np.ndarray, np.ndarray]]) -> Any:
    """Dolan-Moré performance profiles, one step line per preset (log2 of the ratio to the fastest)."""
    import plotly.graph_objects as go

    fig = go.Figure()
    for preset, (ratios, share) in profile.items():
        x = np.concatenate([[1.0], ratios])
        y = np.concatenate([[0.0], share])
        fig.add_trace(
            go.Scatter(
                x=x,
                y=y,
                mode="lines+markers",
                line_shape="hv",
                name=preset,
                marker={"size": 4},
                hovertemplate=f"{preset}: %{{y:.0%}} of models within %{{x:.3g}}× the fastest<extra></extra>",
            )
        )
    fig.update_xaxes(title_text="τ: time over the fastest preset's time (log scale)", type="log")
    fig.update_yaxes(title_text="share of models solved within τ", range=[0, 1.05], tickformat=".0%")
    return _layout(fig, None, 440)


def bench_times(table: pd.DataFrame) -> Any:
    """Solver time against model size, one series per preset, one symbol per structure (proven optimal only)."""
    import plotly.graph_objects as go

    done = table[table["status"] == "optimal"]
    symbols = ["circle", "square", "diamond", "triangle-up", "cross"]
    structures = list(dict.fromkeys(table["structure"]))
    fig = go.Figure()
    for preset, g in done.groupby("preset", sort=True):
        for j, structure in enumerate(structures):
            h = g[g["structure"] == structure].sort_values("cols")
            if h.empty:
                continue
            fig.add_trace(
                go.Scatter(
                    x=h["cols"].to_numpy(),
                    y=(h["total_s"].to_numpy(dtype=float) * 1e3),
                    text=h["model"].to_numpy(),
                    mode="lines+markers",
                    name=f"{preset} ({structure})",
                    legendgroup=str(preset),
                    marker={"symbol": symbols[j % len(symbols)], "size": 7},
                    hovertemplate=f"{preset}<br>%{{text}}<br>%{{x}} columns: %{{y:.3g}} ms<extra></extra>",
                )
            )
    fig.update_xaxes(title_text="model columns (log scale)", type="log")
    fig.update_yaxes(title_text="solver time, proven optimal (ms, log scale)", type="log")
    return _layout(fig, None, 480)


def seeds_by_day(
    units: pd.DataFrame, kpis: Sequence[str], runs: Sequence[str], styles: Styles | None = None
) -> Any | None:
    """An evaluation's metrics per day, one chosen in a menu (``units.csv`` layout: day, seed, run, kpi, value):
    each run's mean over the day's seeds as a marker, the seeds' range as an error bar, the runs side by side
    within a day; None when the units hold none of ``kpis`` for ``runs``."""
    import plotly.graph_objects as go

    sel = units[units["kpi"].isin(list(kpis)) & units["run"].isin(list(runs)) & units["value"].notna()]
    kpis = [k for k in kpis if (sel["kpi"] == k).any()]
    if not kpis:
        return None
    stats = sel.groupby(["kpi", "run", "day"], sort=False)["value"].agg(["mean", "min", "max", "count"]).reset_index()
    colors = css_colors([r for r in runs if (stats["run"] == r).any()], styles)
    fig = go.Figure()
    owner: list[str] = []
    for k in kpis:
        for run in runs:
            g = stats[(stats["kpi"] == k) & (stats["run"] == run)].sort_values("day")
            if g.empty:
                continue
            label = plotly_text(run_label(run, styles))
            mean = g["mean"].to_numpy(dtype=float)
            fig.add_trace(
                go.Scatter(
                    x=[d or "(undated)" for d in g["day"].astype(str)],
                    y=mean,
                    mode="markers",
                    name=label,
                    legendgroup=run,
                    visible=k == kpis[0],
                    marker={"color": colors[run], "size": 7},
                    error_y={
                        "type": "data",
                        "symmetric": False,
                        "array": g["max"].to_numpy(dtype=float) - mean,
                        "arrayminus": mean - g["min"].to_numpy(dtype=float),
                        "color": colors[run],
                    },
                    customdata=np.stack([g["min"], g["max"], g["count"]], axis=1),
                    hovertemplate=f"{label}, %{{x}}: mean %{{y:.4~g}} over %{{customdata[2]}} seeds, "
                    "range [%{customdata[0]:.4~g}, %{customdata[1]:.4~g}]<extra></extra>",
                )
            )
            owner.append(k)
    _kpi_menu(fig, kpis, owner)
    fig.update_xaxes(title_text="day", type="category")  # each trace lists its days in order
    fig.update_layout(scattermode="group", scattergap=0.5)  # the runs of a day side by side, not on top
    return _layout(fig, None, 440)


def leaderboard_bars(board: pd.DataFrame, metrics: Sequence[str], styles: Styles | None = None) -> Any:
    """Each run's mean of a metric (chosen in the menu) with its bootstrap interval as error bars; the competitive
    ratio's two ends as one entry: bars at the mean of saving / U, diamonds at the mean of saving / LB."""
    import plotly.graph_objects as go

    runs = list(dict.fromkeys(str(r) for r in board["run"]))
    colors = css_colors(runs, styles)
    fig = go.Figure()
    owner: list[str] = []
    metrics = interval_metrics([m for m in metrics if (board["kpi"] == m).any()])
    for k in metrics:
        for end, kpi in enumerate(RATIO_ENDS if k == RATIO_INTERVAL else (k,)):
            sel = board[board["kpi"] == kpi]
            trace = go.Bar if end == 0 else go.Scatter
            fig.add_trace(
                trace(
                    x=[plotly_text(run_label(str(r), styles)) for r in sel["run"]],
                    y=sel["mean"].to_numpy(dtype=float),
                    error_y={
                        "type": "data",
                        "symmetric": False,
                        "array": (sel["ci_high"] - sel["mean"]).to_numpy(dtype=float),
                        "arrayminus": (sel["mean"] - sel["ci_low"]).to_numpy(dtype=float),
                    },
                    visible=k == metrics[0],
                    name=KPI_LABELS.get(kpi, kpi),
                    customdata=np.stack([sel["ci_low"], sel["ci_high"]], axis=1),
                    hovertemplate="%{x}: %{y:.4~g} [%{customdata[0]:.4~g}, %{customdata[1]:.4~g}]<extra></extra>",
                    **(
                        {"marker_color": [colors[str(r)] for r in sel["run"]]}
                        if end == 0
                        else {"mode": "markers", "marker": {"symbol": "diamond", "color": "black", "size": 8}}
                    ),
                )
            )
            owner.append(k)
    _kpi_menu(fig, metrics, owner)
    names = list(dict.fromkeys(str(r) for r in board["run"]))  # long names wrap instead of running together
    fig.update_xaxes(
        tickvals=[plotly_text(run_label(r, styles)) for r in names],
        ticktext=[tick_text(run_label(r, styles)) for r in names],
    )
    fig.update_layout(showlegend=False)
    if RATIO_INTERVAL in metrics:
        fig.add_annotation(
            text=f"competitive ratio: {INTERVAL_MARKS}", xref="paper", yref="paper", x=1, y=1.0, xanchor="right",
            yanchor="bottom", showarrow=False, font={"size": 10},
        )  # fmt: skip
    return _layout(fig, None, 440)
