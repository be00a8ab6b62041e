"""Figures for reports (matplotlib, headless), each a pure function of tables read from result files, written
as PNG and, on request, as SVG and PDF beside it (``formats``: :func:`rpbench.spec.figure_formats`).

Every axis says what it measures and in which unit; a legend lists only the runs drawn in its panel, and a
run keeps its colour (:func:`rpbench.results.runs.run_color`) across the panels of a figure.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.results.metrics import KPI_LABELS, KPI_ORDER
from rpbench.results.runs import Styles, run_color, run_label
from rpbench.spec import DEFAULT_FIGURE_FORMATS

#: The competitive ratio drawn as its interval [saving / U, saving / LB] (docs/simulator.md): the pseudo-KPI of
#: the panels and menus that draw it, from its two ends.
RATIO_INTERVAL = "competitive_ratio_interval"
RATIO_ENDS = ("competitive_ratio_bound", "competitive_ratio_best_known")
#: The KPIs of a multi-day report's per-day plots (PNG and report.html); the competitive ratio as its interval.
MULTIDAY_PLOT_KPIS = [k for k in KPI_ORDER if k != "platform_profit_cny"] + [RATIO_INTERVAL, "saving_over_oracle1"]
#: What the interval's marks mean, in a title or caption.
INTERVAL_MARKS = "low end: saving / upper bound U; ◆ saving / best known schedule LB"
#: What a report says of its figures' formats (the same words whichever were written: a report is a function
#: of the folder's tables alone).
FORMATS_NOTE = (
    "Figures are PNG; SVG and PDF copies are written beside them on request (`--figures png,svg,pdf` on the "
    "command that writes the folder, or later `rpbench report PATH --figures svg,pdf`)"
)
HOURLY_PANELS = [
    ("avg_shared_m", "(a) Average shared distance (m)"),
    ("avg_detour_m", "(b) Average detour (m)"),
    ("total_saving_km", "(c) Distance saving (km)"),
    ("response_rate", "(d) Response rate"),
]
#: The y-axis label of each KPI: what is measured, in which unit (ratios: what over what).
KPI_AXES = {
    "response_rate": "response rate (served / orders)",
    "pairing_ratio": "pairing ratio (pooled / served)",
    "pairing_ratio_of_orders": "pooled / orders",
    "platform_profit_cny": "platform profit (CNY)",
    "platform_profit_alt_cny": "platform profit (CNY)",
    "avg_response_time_s": "response time (s)",
    "avg_pickup_time_s": "pick-up time (s)",
    "avg_pickup_distance_m": "pick-up distance (m)",
    "avg_detour_m": "detour per pooled passenger (m)",
    "avg_shared_m": "shared distance per pooled passenger (m)",
    "total_occupied_km": "occupied driving (km)",
    "total_saving_km": "distance saving (km)",
    "competitive_ratio_bound": "saving / proven upper bound",
    "competitive_ratio_best_known": "saving / best known schedule's saving",
    RATIO_INTERVAL: "saving / OPT, an interval",
    "saving_over_oracle1": "saving / Oracle-1's saving",
    "bound_over_best_known": "upper bound / best known saving",
    "best_known_saving_km": "best known saving (km)",
    "decision_p50_s": "decision time per round (s)",
    "decision_p95_s": "decision time per round (s)",
    "decision_max_s": "decision time per round (s)",
    "rounds_over_dt": "rounds slower than Δt",
    "rounds_over_budget": "rounds slower than the decision budget",
}
#: The headline KPIs of a comparison's bar panels (:func:`kpi_figure`): key, panel title.
KPI_PANELS = [
    ("total_saving_km", "Total distance saving"),
    ("pairing_ratio", "Pairing ratio"),
    ("response_rate", "Response rate"),
    ("avg_detour_m", "Average detour"),
    ("avg_pickup_time_s", "Average pick-up time"),
    (RATIO_INTERVAL, "Competitive ratio: bar saving / U, ◆ saving / LB"),
]
#: The panels of :func:`timeline_figure`: state (:data:`rpbench.results.metrics.TIMELINE_STATES`), title.
TIMELINE_PANELS = [
    ("waiting", "(a) Waiting: requested, not yet assigned nor cancelled"),
    ("serving", "(b) Being served: assigned, not yet dropped off"),
    ("pooled", "(c) Riding pooled: on board with the partner aboard"),
    ("cancelled", "(d) Cancelled so far"),
]
#: Sweep parameters (the sweep aliases) as axis labels.
PARAMETER_AXES = {
    "K": "patience K (s)",
    "dt": "batch interval Δt (s)",
    "r_w": "presumed response rate r_w",
    "ratio": "vehicles per 100 orders",
}
_UNIT_SUFFIXES = {"_s": "s", "_m": "m", "_km": "km", "_mps": "m/s", "_cny": "CNY"}
_TAB10 = [
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
]


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def warm_up() -> None:
    """Import matplotlib (headless) ahead of the first figure: a process that draws later can pay for the
    import while it would otherwise wait."""
    _pyplot()


def _savefig(fig: Any, path: Path, formats: Sequence[str]) -> None:
    """The figure in each of ``formats`` (``path``, a ``.png`` name, with the format's suffix), the vector
    copies written without a date, so that the same tables give the same files."""
    import matplotlib

    for form in formats:
        target = path.with_suffix(f".{form}")
        if form == "png":
            fig.savefig(target, dpi=110)
        elif form == "svg":
            with matplotlib.rc_context({"svg.hashsalt": "rpbench"}):
                fig.savefig(target, metadata={"Date": None})
        elif form == "pdf":
            fig.savefig(target, metadata={"CreationDate": None, "ModDate": None})
        else:
            raise ValueError(f"unknown figure format {form!r}")


def _save(
    plt: Any,
    fig: Any,
    path: Path,
    title: str,
    rect: tuple[float, float, float, float] | None = None,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """Title (wrapped: scenario labels are long), lay out, write the figure in ``formats``, free it."""
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=10)
    fig.tight_layout(rect=rect)
    _savefig(fig, path, formats)
    plt.close(fig)
    return path


def run_colors(runs: Sequence[str], styles: Styles | None = None) -> dict[str, str]:
    """Each run's colour: its own, unless a built-in (or an earlier run) of ``runs`` declares it too; else a
    cycle colour no kept colour of ``runs`` is (stable per figure)."""
    from matplotlib.colors import to_hex

    own = {r: run_color(r, styles) for r in runs}
    # a colour a run declares is kept by the first run declaring it (built-ins come first): a later run
    # declaring the same colour, a plug-in say, is drawn in a spare one, as a run without a colour is
    first: dict[str, str] = {}
    for r in sorted(runs, key=lambda r: (_is_plugin(r), runs.index(r))):
        color = own[r]
        if color is not None and to_hex(color) not in first:
            first[to_hex(color)] = r
    keeps = set(first.values())
    taken = set(first)  # "tab:blue" is _TAB10's "#1f77b4"
    spare = [c for c in _TAB10 if c not in taken] or _TAB10
    out, k = {}, 0
    for r in runs:
        color = own[r] if r in keeps else None
        if color is None:
            color, k = spare[k % len(spare)], k + 1
        out[r] = color
    return out


def _is_plugin(run: str) -> bool:
    """A run that is neither a built-in strategy nor an offline run (its colour yields to theirs)."""
    from rpbench.oracle.runs import ORACLE_RUNS
    from rpbench.strategies import STRATEGY_REGISTRY

    return run not in STRATEGY_REGISTRY and run not in ORACLE_RUNS


def axis_label(kpi: str) -> str:
    """The y-axis label of a KPI (:data:`KPI_AXES`; else its table label)."""
    return KPI_AXES.get(kpi, KPI_LABELS.get(kpi, kpi))


def parameter_label(parameter: str) -> str:
    """The axis label of a swept parameter: the aliases by name, a Params field with its unit suffix."""
    if parameter in PARAMETER_AXES:
        return PARAMETER_AXES[parameter]
    for suffix, unit in _UNIT_SUFFIXES.items():
        if parameter.endswith(suffix):
            return f"{parameter} ({unit})"
    return parameter


def _legends(fig: Any, axes: Sequence[Any], *, below: bool = True) -> bool:
    """One legend for the figure when every panel draws the same runs (below the panels, or in the first
    panel), else one per panel, each listing the runs drawn there.  True when a legend sits below."""
    drawn = [ax.get_legend_handles_labels() for ax in axes]
    labelled = [(h, lab) for h, lab in drawn if lab]
    if not labelled:
        return False
    if all(lab == labelled[0][1] for _, lab in labelled) and len(labelled) == len(axes):
        handles, labels = labelled[0]
        if below:
            fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 8), fontsize=8, frameon=False)
            return True
        axes[0].legend(handles, labels, fontsize=8)
        return False
    for ax, (_, lab) in zip(axes, drawn, strict=True):
        if lab:
            ax.legend(fontsize=7, framealpha=0.8)
    return False


def hourly_figure(
    hourly: pd.DataFrame,
    path: Path,
    title: str,
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """The paper's 24-hour comparison: four panels, one line per run (``hourly.csv`` layout)."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.4), sharex=True)
    colors = run_colors(list(dict.fromkeys(hourly["run"])), styles)
    for ax, (col, name) in zip(axes.ravel(), HOURLY_PANELS, strict=True):
        for run, g in hourly.groupby("run", sort=False):
            if g[col].notna().any():  # a run without this KPI (an oracle's response rate) is not drawn
                label = run_label(str(run), styles)
                ax.plot(g["hour"], g[col], marker="o", ms=3, label=label, color=colors[str(run)])
        ax.set_title(name, fontsize=10)
        ax.set_ylabel(axis_label(col), fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("hour of day (request time)", fontsize=9)
    below = _legends(fig, list(axes.ravel()))
    return _save(plt, fig, path, title, rect=(0, 0.05, 1, 1) if below else None, formats=formats)


def per_day_figures(
    by_day: pd.DataFrame,
    folder: Path,
    kpis: list[str],
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> list[Path]:
    """One figure per KPI: value per day, one series per run (``by_day`` columns date, run, kpi, value);
    :data:`RATIO_INTERVAL` draws each run's competitive ratio per day as its interval.

    Days are discrete: one tick per day on a categorical axis, and markers, not lines, since nothing lies
    between two days; runs are offset a little within a day so that equal values stay visible."""
    plt = _pyplot()
    paths = []
    colors = run_colors(list(dict.fromkeys(by_day["run"])), styles)
    days = sorted(set(by_day["date"].astype(str)))
    position = {d: i for i, d in enumerate(days)}
    runs = list(dict.fromkeys(str(r) for r in by_day["run"]))
    width = 0.6 / max(len(runs), 1)
    for kpi in kpis:
        if kpi == RATIO_INTERVAL:
            sel = interval_rows(by_day)
        else:
            sel = by_day[(by_day["kpi"] == kpi) & by_day["value"].notna()]  # only runs with data are drawn
        if sel.empty:
            continue
        fig, ax = plt.subplots(figsize=(9.5, 3.6))
        for run, g in sel.groupby("run", sort=False):
            shift = (runs.index(str(run)) - (len(runs) - 1) / 2) * width
            x = np.array([position[str(d)] + shift for d in g["date"]])
            style = {"label": run_label(str(run), styles), "color": colors[str(run)]}
            if kpi != RATIO_INTERVAL:
                ax.plot(x, g["value"], marker="o", ms=4, linestyle="none", **style)
                continue
            low, high = g["low"].to_numpy(dtype=float), g["high"].to_numpy(dtype=float)
            ax.vlines(x, np.where(np.isnan(low), 0.0, low), high, color=colors[str(run)], lw=1.6)
            ax.plot(x, low, marker="o", ms=4, linestyle="none", **style)
            ax.plot(x, high, marker="D", ms=4, linestyle="none", color=colors[str(run)])
        ax.set_xticks(range(len(days)), days, rotation=45, ha="right", fontsize=8)
        ax.set_xlim(-0.5, len(days) - 0.5)
        interval = "Competitive ratio per day: ● saving / upper bound up to ◆ saving / best known schedule"
        ax.set_title(interval if kpi == RATIO_INTERVAL else KPI_LABELS.get(kpi, kpi), fontsize=10)
        ax.set_xlabel("day", fontsize=9)
        ax.set_ylabel(axis_label(kpi), fontsize=9)
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))  # beside: markers fill the plot
        fig.tight_layout()
        path = folder / f"by_day_{kpi}.png"
        _savefig(fig, path, formats)
        plt.close(fig)
        paths.append(path)
    return paths


def interval_rows(tidy: pd.DataFrame, x: str = "date") -> pd.DataFrame:
    """Per ``x`` and run of a tidy table (``x``, run, kpi, value): the competitive ratio's ends ``low``
    (saving / U) and ``high`` (saving / LB), where either is defined."""
    sel = tidy[tidy["kpi"].isin(RATIO_ENDS)]
    ends = {k: sel[sel["kpi"] == k].set_index([x, "run"])["value"] for k in RATIO_ENDS}
    wide = pd.DataFrame({"low": ends[RATIO_ENDS[0]], "high": ends[RATIO_ENDS[1]]}).dropna(how="all")
    order = list(dict.fromkeys(zip(sel[x], sel["run"], strict=True)))
    return wide.reindex([k for k in order if k in wide.index]).reset_index()


def leaderboard_figure(
    board: pd.DataFrame,
    metrics: Sequence[str],
    path: Path,
    title: str,
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """An evaluation's leaderboard (``leaderboard.csv`` layout): one panel per metric, each run's mean as a bar
    with its bootstrap interval as an error bar; a panel shows only the runs with a value.  The competitive
    ratio's two ends share one panel (:func:`_leaderboard_interval`)."""
    plt = _pyplot()
    metrics = interval_metrics([m for m in metrics if (board["kpi"] == m).any()])
    ncols = min(3, max(len(metrics), 1))
    nrows = max(1, -(-len(metrics) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(4 * ncols, 3.6 * nrows), squeeze=False)
    colors = run_colors(list(dict.fromkeys(str(r) for r in board["run"])), styles)
    for ax, kpi in zip(axes.ravel(), metrics, strict=False):
        ax.set_ylabel(axis_label(kpi), fontsize=9)
        ax.axhline(0, color="black", lw=0.6)
        ax.grid(alpha=0.3, axis="y")
        if kpi == RATIO_INTERVAL:
            _leaderboard_interval(ax, board, colors, styles)
            continue
        sel = board[(board["kpi"] == kpi) & board["mean"].notna()]
        runs = [str(r) for r in sel["run"]]
        mean = sel["mean"].to_numpy(dtype=float)
        below = mean - sel["ci_low"].to_numpy(dtype=float)
        above = sel["ci_high"].to_numpy(dtype=float) - mean
        x = np.arange(len(runs))
        ax.bar(x, mean, color=[colors[r] for r in runs], width=0.7)
        ax.errorbar(x, mean, yerr=np.vstack([below, above]), fmt="none", ecolor="black", elinewidth=1, capsize=3)
        ax.set_xticks(x, [run_label(r, styles) for r in runs], rotation=35, ha="right", fontsize=8)
        ax.set_title(KPI_LABELS.get(kpi, kpi).split(" (")[0], fontsize=10)
    for ax in axes.ravel()[len(metrics) :]:
        ax.set_visible(False)
    return _save(plt, fig, path, title, formats=formats)


def interval_metrics(metrics: Sequence[str]) -> list[str]:
    """``metrics`` with the competitive ratio's two ends, when both are there, drawn as one
    :data:`RATIO_INTERVAL` in the place of the first."""
    metrics = list(metrics)
    if not set(RATIO_ENDS) <= set(metrics):
        return metrics
    first = min(metrics.index(k) for k in RATIO_ENDS)
    rest = [m for m in metrics if m not in RATIO_ENDS]
    return [*rest[:first], RATIO_INTERVAL, *rest[first:]]


def _leaderboard_interval(ax: Any, board: pd.DataFrame, colors: dict[str, str], styles: Styles | None) -> None:
    """Each run's mean competitive ratio as an interval: a bar up to the mean of saving / U, a segment up to a
    diamond at the mean of saving / LB, each end with its bootstrap interval."""
    ends = [board[(board["kpi"] == k) & board["mean"].notna()].set_index("run") for k in RATIO_ENDS]
    runs = [str(r) for r in dict.fromkeys([*ends[0].index, *ends[1].index])]
    x = np.arange(len(runs))

    def column(end: pd.DataFrame, name: str) -> np.ndarray:
        return np.array([float(end.loc[r, name]) if r in end.index else np.nan for r in runs])

    low, high = column(ends[0], "mean"), column(ends[1], "mean")
    bars = ~np.isnan(low)
    ax.bar(x[bars], low[bars], color=[colors[r] for r, b in zip(runs, bars, strict=True) if b], width=0.7)
    side = x + 0.2  # the upper end beside the bar's own interval, so that the two intervals stay apart
    ax.vlines(side, np.where(bars, low, 0.0), high, colors="black", lw=1.2, linestyles=":")
    ax.plot(side, high, marker="D", ms=5, ls="none", color="black")
    for end, at, mean, color in ((ends[0], x, low, "black"), (ends[1], side, high, "grey")):
        err = np.vstack([mean - column(end, "ci_low"), column(end, "ci_high") - mean])
        ax.errorbar(at, mean, yerr=err, fmt="none", ecolor=color, elinewidth=1, capsize=3)
    ax.set_xticks(x, [run_label(r, styles) for r in runs], rotation=35, ha="right", fontsize=8)
    ax.set_title(f"Competitive ratio ({INTERVAL_MARKS})", fontsize=8)


def seeds_by_day_figure(
    units: pd.DataFrame,
    kpi: str,
    runs: Sequence[str],
    path: Path,
    title: str,
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path | None:
    """One metric of an evaluation per day (``units.csv`` layout: day, seed, run, kpi, value): each run's mean
    over the day's seeds as a marker, the seeds' range as an error bar; days on a categorical axis."""
    sel = units[(units["kpi"] == kpi) & units["run"].isin(list(runs)) & units["value"].notna()]
    if sel.empty:
        return None
    plt = _pyplot()
    stats = sel.groupby(["run", "day"], sort=False)["value"].agg(["mean", "min", "max"]).reset_index()
    days = sorted(set(stats["day"].astype(str)))
    position = {d: i for i, d in enumerate(days)}
    drawn = [r for r in runs if (stats["run"] == r).any()]
    colors = run_colors(list(drawn), styles)
    width = 0.6 / max(len(drawn), 1)
    fig, ax = plt.subplots(figsize=(9.5, 3.8))
    for i, run in enumerate(drawn):
        g = stats[stats["run"] == run]
        x = np.array([position[str(d)] for d in g["day"]]) + (i - (len(drawn) - 1) / 2) * width
        mean = g["mean"].to_numpy(dtype=float)
        yerr = np.vstack([mean - g["min"].to_numpy(dtype=float), g["max"].to_numpy(dtype=float) - mean])
        ax.errorbar(x, mean, yerr=yerr, fmt="o", ms=4, capsize=2, elinewidth=1, color=colors[run],
                    label=run_label(run, styles))  # fmt: skip
    ax.set_xticks(range(len(days)), [d or "(undated)" for d in days], rotation=45, ha="right", fontsize=8)
    ax.set_xlim(-0.5, len(days) - 0.5)
    ax.set_xlabel("day", fontsize=9)
    ax.set_ylabel(axis_label(kpi), fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return _save(plt, fig, path, title, formats=formats)


def sweep_figure(
    table: pd.DataFrame,
    parameter: str,
    kpis: list[str],
    path: Path,
    title: str,
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """KPIs against a swept parameter (``table`` columns value, run, kpi, value_kpi)."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(kpis), figsize=(3.6 * len(kpis), 3.8), squeeze=False)
    colors = run_colors(list(dict.fromkeys(table["run"])), styles)
    for ax, kpi in zip(axes[0], kpis, strict=True):
        sel = table[(table["kpi"] == kpi) & table["value"].notna()]
        for run, g in sel.groupby("run", sort=False):
            label = run_label(str(run), styles)
            ax.plot(g["point"], g["value"], marker="o", ms=3, label=label, color=colors[str(run)])
        ax.set_xlabel(parameter_label(parameter), fontsize=9)
        ax.set_ylabel(axis_label(kpi), fontsize=9)
        ax.set_title(KPI_LABELS.get(kpi, kpi).split(" (")[0], fontsize=9)
        ax.grid(alpha=0.3)
    below = _legends(fig, list(axes[0]))
    return _save(plt, fig, path, title, rect=(0, 0.08, 1, 1) if below else None, formats=formats)


def interval_ends(table: pd.DataFrame) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The runs of ``table`` (KPI rows x run columns) with a competitive ratio, and its two ends: saving / U
    (NaN without a bound) and saving / LB (NaN when LB is not > 0)."""
    rows = [table.loc[k] if k in table.index else pd.Series(np.nan, index=table.columns) for k in RATIO_ENDS]
    runs = [str(r) for r in table.columns if pd.notna(rows[0][r]) or pd.notna(rows[1][r])]
    low = np.array([float(rows[0][r]) for r in runs], dtype=float)
    high = np.array([float(rows[1][r]) for r in runs], dtype=float)
    return runs, low, high


def _has_panel(table: pd.DataFrame, kpi: str) -> bool:
    if kpi == RATIO_INTERVAL:
        return bool(interval_ends(table)[0])
    return kpi in table.index and bool(table.loc[kpi].notna().any())


def _interval_panel(ax: Any, table: pd.DataFrame, colors: dict[str, str], text: Callable[[str, float], str],
                    styles: Styles | None) -> None:  # fmt: skip
    """Each run's competitive ratio as its interval: a bar up to saving / U, a segment from there up to a
    diamond at saving / LB (from 0 without a bound), both ends written above."""
    runs, low, high = interval_ends(table)
    x = np.arange(len(runs))
    bars = ~np.isnan(low)
    ax.bar(x[bars], low[bars], color=[colors[r] for r, b in zip(runs, bars, strict=True) if b], width=0.7)
    tops = ~np.isnan(high)
    base = np.where(bars, low, 0.0)
    ax.vlines(x[tops], base[tops], high[tops], colors="black", lw=1.4)
    ax.plot(x[tops], high[tops], marker="D", ms=5, ls="none", color="black")
    top = float(np.nanmax(np.r_[low, high, 1.0]))
    for xi, lo, hi in zip(x, low, high, strict=True):
        ends = [text(k, v) for k, v in zip(RATIO_ENDS[::-1], (hi, lo), strict=True) if not np.isnan(v)]
        ax.text(xi, np.nanmax([lo, hi, 0.0]) + 0.04 * top, "\n".join(ends), ha="center", va="bottom", fontsize=6)
    ax.set_ylim(0, top * 1.3)
    ax.set_xticks(x, [run_label(r, styles) for r in runs], rotation=35, ha="right", fontsize=8)


def kpi_figure(
    table: pd.DataFrame,
    path: Path,
    title: str,
    text: Callable[[str, float], str],
    styles: Styles | None = None,
    *,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """The headline KPIs of a comparison (:data:`KPI_PANELS`), one bar per run with its value on top.

    ``table`` is the wide KPI table (KPI rows x run columns, as :func:`rpbench.report.comparison.load_kpis`);
    a panel shows only the runs with a value (offline runs have no response rate), the competitive ratio
    as an interval (:func:`_interval_panel`, simulated runs only); ``text(kpi, value)`` writes the value as
    the report's tables do.
    """
    plt = _pyplot()
    panels = [(k, name) for k, name in KPI_PANELS if _has_panel(table, k)]
    ncols = 3
    nrows = max(1, -(-len(panels) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(12, 3.7 * nrows), squeeze=False)
    runs = [str(r) for r in table.columns]
    colors = run_colors(runs, styles)
    for ax, (kpi, name) in zip(axes.ravel(), panels, strict=False):
        ax.set_title(name, fontsize=10)
        ax.set_ylabel(axis_label(kpi), fontsize=9)
        ax.grid(alpha=0.3, axis="y")
        if kpi == RATIO_INTERVAL:
            _interval_panel(ax, table, colors, text, styles)
            continue
        row = table.loc[kpi]
        shown = [r for r in runs if pd.notna(row[r])]
        values = np.array([float(row[r]) for r in shown])
        x = np.arange(len(shown))
        ax.bar(x, values, color=[colors[r] for r in shown], width=0.7)
        span = max(float(np.abs(values).max()), 1e-12)
        for xi, v in zip(x, values, strict=True):
            ax.text(
                xi,
                v + (0.02 * span if v >= 0 else -0.02 * span),
                text(kpi, v),
                ha="center",
                va="bottom" if v >= 0 else "top",
                fontsize=7,
            )
        low, high = min(0.0, float(values.min())), max(0.0, float(values.max()))
        ax.set_ylim(low - (0.12 * span if low < 0 else 0), high + 0.12 * span)
        ax.set_xticks(x, [run_label(r, styles) for r in shown], rotation=35, ha="right", fontsize=8)
        ax.axhline(0, color="black", lw=0.6)
    for ax in axes.ravel()[len(panels) :]:
        ax.set_visible(False)
    return _save(plt, fig, path, title, formats=formats)


def timeline_figure(
    timeline: pd.DataFrame,
    path: Path,
    title: str,
    *,
    hours: bool,
    start: str | None,
    bin_s: float,
    horizon_s: float,
    styles: Styles | None = None,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Path:
    """The period's timeline: four panels (:data:`TIMELINE_PANELS`), one line per run.

    ``timeline`` columns run, state, t_s (seconds from the scenario start), value: for waiting, serving
    and pooled the mean count over the ``bin_s`` bin centred on t_s, for cancelled the count by t_s.  The
    x axis is in hours (``hours``) or minutes from the scenario start (``start``: its clock time), with a
    dotted line where requests stop (``horizon_s``).
    """
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.4), sharex=True)
    runs = list(dict.fromkeys(str(r) for r in timeline["run"]))
    colors = run_colors(runs, styles)
    scale = 3600.0 if hours else 60.0
    width = f"{bin_s / 60:g}-min"
    for ax, (state, name) in zip(axes.ravel(), TIMELINE_PANELS, strict=True):
        sel = timeline[timeline["state"] == state]
        for run, g in sel.groupby("run", sort=False):
            ax.plot(g["t_s"] / scale, g["value"], lw=1.2, label=run_label(str(run), styles), color=colors[str(run)])
        ax.axvline(horizon_s / scale, color="grey", ls=":", lw=1)
        ax.set_title(name, fontsize=10)
        ax.set_ylabel("passengers (total)" if state == "cancelled" else f"passengers ({width} mean)", fontsize=9)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    since = f" ({start})" if start else ""
    for ax in axes[1]:
        ax.set_xlabel(f"{'hours' if hours else 'minutes'} since the scenario start{since}", fontsize=9)
    below = _legends(fig, list(axes.ravel()))
    return _save(plt, fig, path, title, rect=(0, 0.05, 1, 1) if below else None, formats=formats)


def bench_figure(
    table: pd.DataFrame, path: Path, title: str, *, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS
) -> Path:
    """Solver time (build + solve + extract) against model size, one panel per structure, one line per preset.

    ``table`` is a :func:`rpbench.bench.runner.run_benchmark` table; rows without a
    proven optimum (verdict ``optimal`` when the table has verdicts) are left out: their time is a time
    limit or a wrong answer's, not a solve.
    """
    plt = _pyplot()
    from matplotlib.ticker import NullFormatter

    done = table[table["verdict"] == "optimal"] if "verdict" in table else table[table["status"] == "optimal"]
    structures = list(dict.fromkeys(table["structure"]))
    fig, axes = plt.subplots(1, len(structures), figsize=(4.2 * len(structures), 3.8), squeeze=False)
    presets = sorted(set(table["preset"]))
    colors = {preset: _TAB10[i % len(_TAB10)] for i, preset in enumerate(presets)}  # one colour across panels
    for ax, structure in zip(axes[0], structures, strict=True):
        for preset, g in done[done["structure"] == structure].groupby("preset", sort=True):
            g = g.sort_values("cols")
            ax.plot(g["cols"], g["total_s"] * 1e3, marker="o", ms=3, label=preset, color=colors[preset])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # decade labels only: minor ones overlap
        ax.set_xlabel("model columns", fontsize=9)
        ax.set_ylabel("solver time, proven optimal (ms)", fontsize=9)
        ax.set_title(structure, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    _legends(fig, list(axes[0]), below=False)
    return _save(plt, fig, path, title, formats=formats)


def profile_figure(
    profile: pd.DataFrame, path: Path, title: str, *, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS
) -> Path:
    """The Dolan-Moré performance profile: one step line per preset, tau on a log axis.

    ``profile`` is a :func:`rpbench.report.bench.performance_profile` table (``preset``, ``tau``,
    ``fraction``); each line is drawn to the largest tau, where it stays at the share its preset solved.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    presets = sorted(set(profile["preset"]))
    top = float(profile["tau"].max()) if len(profile) else 1.0
    right = max(2.0, top * 1.25)
    for i, (preset, g) in enumerate(profile.groupby("preset", sort=True)):
        g = g.sort_values("tau")
        x = np.concatenate([g["tau"].to_numpy(), [right]])
        y = np.concatenate([g["fraction"].to_numpy(), g["fraction"].to_numpy()[-1:]])
        ax.step(x, y, where="post", label=str(preset), color=_TAB10[i % len(_TAB10)], lw=1.6)
    ax.set_xscale("log", base=2)
    ax.set_xlim(1.0, right)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel("τ: time over the fastest preset's time (log scale)", fontsize=9)
    ax.set_ylabel("share of instances solved within τ", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    if presets:
        ax.legend(fontsize=8, loc="lower right")
    return _save(plt, fig, path, title, formats=formats)
