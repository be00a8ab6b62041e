"""The figures of reports: labelled axes with units, legends of the runs drawn, and a toy run's figures."""

from __future__ import annotations

import json

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from rpbench import results
from rpbench.check import check_folder
from rpbench.harness.comparison import run_comparison
from rpbench.report.comparison import fmt, timeline_of
from rpbench.report.plots import (
    RATIO_INTERVAL,
    bench_figure,
    hourly_figure,
    interval_metrics,
    kpi_figure,
    leaderboard_figure,
    per_day_figures,
    seeds_by_day_figure,
    sweep_figure,
)
from rpbench.results.metrics import count_at, state_spells
from rpbench.results.read import load_kpis
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

matplotlib.use("Agg")


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions close, kept open for inspection (closed after the test)."""
    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    yield kept
    monkeypatch.undo()
    plt.close("all")


def panels(fig):
    return [ax for ax in fig.axes if ax.get_visible()]


def legend_runs(ax) -> list[str]:
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend else []


def assert_labelled(fig, *, categorical_x: bool = False):
    """Every panel has a y label; every bottom panel (shared x) an x label, or run names as ticks."""
    for ax in panels(fig):
        assert ax.get_ylabel(), ax.get_title()
        if categorical_x:
            assert all(t.get_text() for t in ax.get_xticklabels()), ax.get_title()
        elif ax.get_subplotspec().is_last_row():
            assert ax.get_xlabel(), ax.get_title()


def hourly_table() -> pd.DataFrame:
    rows = []
    for run in ("mb", "fl", "bound"):
        for h in range(24):
            rows.append(
                {
                    "run": run,
                    "hour": h,
                    "avg_shared_m": 1000.0 + h,
                    "avg_detour_m": 500.0,
                    "total_saving_km": float(h),
                    "response_rate": np.nan if run == "bound" else 0.8,  # an offline run serves no one
                }
            )
    return pd.DataFrame(rows)


def test_hourly_axes_and_legends(tmp_path, figures):
    hourly_figure(hourly_table(), tmp_path / "h.png", "title")
    (fig,) = figures
    assert_labelled(fig)
    by_title = {ax.get_title(): ax for ax in panels(fig)}
    assert by_title["(c) Distance saving (km)"].get_ylabel() == "distance saving (km)"
    assert panels(fig)[-1].get_xlabel() == "hour of day (request time)"
    # the bound has no response rate: that panel's legend does not list it, the others do
    assert legend_runs(by_title["(d) Response rate"]) == ["MB", "FL"]
    assert legend_runs(by_title["(c) Distance saving (km)"]) == ["MB", "FL", "Upper bound"]


def test_one_legend_when_every_panel_draws_the_same_runs(tmp_path, figures):
    table = hourly_table()
    hourly_figure(table[table["run"] != "bound"], tmp_path / "h.png", "title")
    (fig,) = figures
    assert not any(legend_runs(ax) for ax in panels(fig))
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["MB", "FL"]


def test_per_day_axes_list_only_runs_with_data(tmp_path, figures):
    by_day = pd.DataFrame(
        [
            {"date": d, "run": r, "kpi": k, "value": np.nan if (r == "oracle1" and k == "response_rate") else 1.0}
            for d in ("2017-05-01", "2017-05-02")
            for r in ("mb", "oracle1")
            for k in ("response_rate", "total_saving_km")
        ]
    )
    paths = per_day_figures(by_day, tmp_path, ["response_rate", "total_saving_km"])
    assert [p.name for p in paths] == ["by_day_response_rate.png", "by_day_total_saving_km.png"]
    rate, saving = figures
    assert_labelled(rate)
    assert_labelled(saving)
    assert rate.axes[0].get_xlabel() == "day" and rate.axes[0].get_ylabel() == "response rate (served / orders)"
    assert legend_runs(rate.axes[0]) == ["MB"] and legend_runs(saving.axes[0]) == ["MB", "Oracle-1"]
    # discrete days: one tick each on a categorical axis, markers without lines joining the days
    assert [t.get_text() for t in saving.axes[0].get_xticklabels()] == ["2017-05-01", "2017-05-02"]
    assert all(line.get_linestyle() == "None" and line.get_marker() == "o" for line in saving.axes[0].get_lines())


def test_leaderboard_bars_carry_their_intervals(tmp_path, figures):
    board = pd.DataFrame(
        [
            {"run": "mb", "kpi": "total_saving_km", "mean": 10.0, "ci_low": 8.0, "ci_high": 13.0},
            {"run": "fl", "kpi": "total_saving_km", "mean": 12.0, "ci_low": 11.0, "ci_high": 12.5},
            {"run": "mb", "kpi": "response_rate", "mean": 0.9, "ci_low": 0.85, "ci_high": 0.95},
            {"run": "bound", "kpi": "response_rate", "mean": np.nan, "ci_low": np.nan, "ci_high": np.nan},
        ]
    )
    formats = ("png", "svg", "pdf")
    leaderboard_figure(board, ["total_saving_km", "response_rate"], tmp_path / "lb.png", "leaderboard", formats=formats)
    (fig,) = figures
    assert_labelled(fig, categorical_x=True)
    saving, rate = panels(fig)
    assert [t.get_text() for t in saving.get_xticklabels()] == ["MB", "FL"]
    assert [t.get_text() for t in rate.get_xticklabels()] == ["MB"]  # the bound has no response rate
    (bars,) = saving.collections  # the error bars span each interval
    spans = sorted((round(min(seg[:, 1]), 9), round(max(seg[:, 1]), 9)) for seg in bars.get_segments())
    assert spans == [(8.0, 13.0), (11.0, 12.5)]
    assert all((tmp_path / f"lb{suffix}").is_file() for suffix in (".png", ".svg", ".pdf"))


def test_seeds_per_day_are_a_mean_and_the_seeds_range(tmp_path, figures):
    units = pd.DataFrame(
        [
            {"day": d, "seed": s, "run": r, "kpi": "total_saving_km", "value": v + s}
            for d, v in (("2017-05-01", 10.0), ("2017-05-02", 20.0))
            for s in (0, 1, 2)
            for r in ("mb", "fl")
        ]
    )
    seeds_by_day_figure(units, "total_saving_km", ["mb", "fl", "np"], tmp_path / "d.png", "per day")
    (fig,) = figures
    (ax,) = panels(fig)
    assert legend_runs(ax) == ["MB", "FL"] and ax.get_xlabel() == "day"
    assert [t.get_text() for t in ax.get_xticklabels()] == ["2017-05-01", "2017-05-02"]
    means = sorted(float(y) for line in ax.get_lines() if line.get_marker() == "o" for y in line.get_ydata())
    assert means == [11.0, 11.0, 21.0, 21.0]  # seeds 0-2 around each day's value
    spans = {(round(min(seg[:, 1]), 9), round(max(seg[:, 1]), 9)) for c in ax.collections for seg in c.get_segments()}
    assert spans == {(10.0, 12.0), (20.0, 22.0)}
    assert seeds_by_day_figure(units, "response_rate", ["mb"], tmp_path / "none.png", "none") is None


def test_sweep_axes_name_the_parameter_with_its_unit(tmp_path, figures):
    table = pd.DataFrame(
        [
            {"point": v, "label": f"dt={v}", "run": r, "kpi": k, "value": float(v)}
            for v in (2, 10)
            for r in ("mb", "fl")
            for k in ("avg_detour_m", "response_rate")
        ]
    )
    sweep_figure(table, "dt", ["avg_detour_m", "response_rate"], tmp_path / "s.png", "sweep")
    (fig,) = figures
    assert_labelled(fig)
    assert {ax.get_xlabel() for ax in panels(fig)} == {"batch interval Δt (s)"}
    assert panels(fig)[0].get_ylabel() == "detour per pooled passenger (m)"
    sweep_figure(table, "planner_patience_s", ["avg_detour_m"], tmp_path / "s2.png", "sweep")
    assert panels(figures[1])[0].get_xlabel() == "planner_patience_s (s)"


def test_bench_axes_and_a_preset_colour_per_preset(tmp_path, figures):
    table = pd.DataFrame(
        [
            {"structure": s, "preset": p, "status": "optimal", "cols": c, "total_s": 0.001 * c}
            for s in ("assignment", "packing")
            for p in (("highs", "jv") if s == "assignment" else ("highs",))
            for c in (10, 100)
        ]
    )
    bench_figure(table, tmp_path / "b.png", "bench")
    (fig,) = figures
    assert_labelled(fig)
    assignment, packing = panels(fig)
    assert assignment.get_xlabel() == "model columns" and packing.get_ylabel() == "solver time, proven optimal (ms)"
    assert legend_runs(assignment) == ["highs", "jv"] and legend_runs(packing) == ["highs"]
    assert assignment.get_lines()[0].get_color() == packing.get_lines()[0].get_color()


def test_kpi_bars_leave_out_runs_without_the_kpi(tmp_path, figures):
    table = pd.DataFrame(
        {"np": [0.0, 0.8, np.nan], "mb": [111.0, 0.9, 900.0], "oracle1": [250.0, np.nan, 940.0]},
        index=["total_saving_km", "response_rate", "avg_detour_m"],
    )
    kpi_figure(table, tmp_path / "k.png", "title", fmt)
    (fig,) = figures
    assert_labelled(fig, categorical_x=True)
    by_title = {ax.get_title(): ax for ax in panels(fig)}
    assert set(by_title) == {"Total distance saving", "Response rate", "Average detour"}  # no ratio without a bound
    ticks = {t: [x.get_text() for x in ax.get_xticklabels()] for t, ax in by_title.items()}
    assert ticks == {
        "Total distance saving": ["NP", "MB", "Oracle-1"],
        "Response rate": ["NP", "MB"],
        "Average detour": ["MB", "Oracle-1"],
    }
    assert by_title["Total distance saving"].get_ylabel() == "distance saving (km)"
    # each bar carries its value as the report's tables print it
    assert [t.get_text() for t in by_title["Total distance saving"].texts] == ["0.0", "111", "250"]


def test_the_competitive_ratio_is_drawn_as_its_interval(tmp_path, figures):
    """A bar up to saving / U, a segment from there up to a diamond at saving / LB; offline runs have none."""
    table = pd.DataFrame(
        {"mb": [60.0, 0.5, 0.6], "hindsight": [100.0, 0.8333, 1.0], "bound": [120.0, np.nan, np.nan]},
        index=["total_saving_km", "competitive_ratio_bound", "competitive_ratio_best_known"],
    )
    kpi_figure(table, tmp_path / "k.png", "title", fmt)
    (fig,) = figures
    ratio = next(ax for ax in panels(fig) if ax.get_title().startswith("Competitive ratio"))
    assert [t.get_text() for t in ratio.get_xticklabels()] == ["MB", "Hindsight (clairvoyant)"]
    assert [round(p.get_height(), 4) for p in ratio.patches] == [0.5, 0.8333]  # the bars: saving / U
    (segments,) = ratio.collections
    assert [tuple(np.round(seg[:, 1], 4)) for seg in segments.get_segments()] == [(0.5, 0.6), (0.8333, 1.0)]
    assert [t.get_text() for t in ratio.texts] == ["0.600\n0.500", "1.000\n0.833"]  # both ends written


def test_the_ratio_per_day_and_in_a_leaderboard_is_an_interval(tmp_path, figures):
    by_day = pd.DataFrame(
        [
            {"date": d, "run": "mb", "kpi": k, "value": v}
            for d in ("2017-05-01", "2017-05-02")
            for k, v in (("competitive_ratio_bound", 0.4), ("competitive_ratio_best_known", 0.7))
        ]
    )
    (path,) = per_day_figures(by_day, tmp_path, [RATIO_INTERVAL])
    assert path.name == "by_day_competitive_ratio_interval.png"
    (day,) = figures
    (segments,) = day.axes[0].collections
    assert [tuple(seg[:, 1]) for seg in segments.get_segments()] == [(0.4, 0.7), (0.4, 0.7)]
    assert interval_metrics(["total_saving_km", "competitive_ratio_bound", "competitive_ratio_best_known"]) == [
        "total_saving_km",
        RATIO_INTERVAL,
    ]
    board = pd.DataFrame(
        [
            {"run": "mb", "kpi": k, "mean": m, "ci_low": m - 0.1, "ci_high": m + 0.1}
            for k, m in (("competitive_ratio_bound", 0.4), ("competitive_ratio_best_known", 0.7))
        ]
    )
    leaderboard_figure(board, ["competitive_ratio_bound", "competitive_ratio_best_known"], tmp_path / "l.png", "t")
    (ratio,) = panels(figures[-1])
    assert [round(p.get_height(), 6) for p in ratio.patches] == [0.4] and ratio.get_title().startswith("Competitive")


# ------------------------------------------------------------------------------------------- a toy run
@pytest.fixture(scope="module")
def toy_run(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2, seed=5), ["np", "mb", "bound"])
    folder = run_comparison(spec, tmp_path_factory.mktemp("runs") / "toy", progress=False).folder
    return folder


def test_a_toy_run_has_its_figures(toy_run):
    report = (toy_run / "report.md").read_text()
    for png in ("kpis.png", "timeline.png"):
        assert (toy_run / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"]({png})" in report
    assert not (toy_run / "hourly.png").exists()  # one hour: no per-hour plot
    assert "The offline runs (Upper bound) pair orders after the fact" in report
    assert report.index("Synthetic city, not Haikou") < report.index("## Comparison")


def direct_counts(events: pd.DataFrame, t: float) -> dict[str, int]:
    """The states at ``t`` from a per-order pivot of the log (an event at t has happened at t)."""
    ev = events[events["order"] >= 0]
    at = ev.pivot_table(index="order", columns="event", values="t_s", aggfunc="first") <= t
    at = at.reindex(columns=["request", "assign", "pickup", "dropoff", "cancel"], fill_value=False)
    links = events[(events["event"] == "assign") & (events["partner"] >= 0)]
    mates = pd.concat(
        [links.set_index("order")["partner"], links.set_index("partner")["order"]]
    )  # the first passenger of a join is named only by the second's event
    aboard = at["pickup"] & ~at["dropoff"]
    partner_aboard = aboard.reindex(mates.reindex(at.index).to_numpy()).fillna(False).to_numpy()
    return {
        "waiting": int((at["request"] & ~at["assign"] & ~at["cancel"]).sum()),
        "serving": int((at["assign"] & ~at["dropoff"]).sum()),
        "pooled": int((aboard.to_numpy() & partner_aboard).sum()),
        "cancelled": int(at["cancel"].sum()),
    }


def test_the_timeline_counts_what_the_event_log_holds(toy_run):
    events = results.read_csv(toy_run / "runs" / "mb" / "events.csv.gz")
    spells = state_spells(events)
    instants = [0.0, 300.0, 900.0, 1800.5, 2700.0, 3600.0, float(events["t_s"].max())]
    for t in instants:
        counted = {state: int(count_at(spells[state], np.array([t]))[0]) for state in spells}
        assert counted == direct_counts(events, t)
    assert any(direct_counts(events, t)["pooled"] > 0 for t in instants)  # the instants see pooled riders
    timeline = timeline_of(toy_run)
    assert not isinstance(timeline, str) and timeline.offline == ["bound"] and not timeline.hours
    cancelled = timeline.table.query("run == 'mb' and state == 'cancelled'")
    for t, value in zip(cancelled["t_s"], cancelled["value"], strict=True):
        assert value == direct_counts(events, t)["cancelled"]
    # a bin's mean is the time average of the counts: sampled finely, the same number
    waiting = timeline.table.query("run == 'np' and state == 'waiting'").iloc[10]
    np_events = results.read_csv(toy_run / "runs" / "np" / "events.csv.gz")
    half = timeline.bin_s / 2
    grid = np.linspace(waiting["t_s"] - half, waiting["t_s"] + half, 601)[:-1] + timeline.bin_s / 1200
    sampled = np.mean([direct_counts(np_events, t)["waiting"] for t in grid])
    assert sampled > 0 and waiting["value"] == pytest.approx(sampled, abs=0.05)


def test_np_saves_exactly_nothing_and_the_checker_agrees(toy_run):
    table = load_kpis(toy_run)
    assert table.loc["pairs", "np"] == 0
    assert table.loc["total_saving_km", "np"] == 0.0 and table.loc["competitive_ratio_bound", "np"] == 0.0
    assert json.loads((toy_run / "meta.json").read_text())["runs"]["np"]["kind"] == "simulation"
    assert all(rc.ok for rc in check_folder(toy_run))


def test_a_plugin_declaring_a_builtins_colour_is_drawn_in_another():
    """MB keeps its blue even when a plug-in listed before it declares blue too; runs without a colour of
    their own, and the plug-in, get spare colours no kept run uses."""
    from matplotlib.colors import to_hex

    from rpbench.report.plots import run_colors

    styles = {"mine": ("Mine", "tab:blue"), "other": ("Other", None)}
    colors = run_colors(["mine", "mb", "rtv", "other"], styles)
    assert colors["mb"] == "tab:blue" and colors["rtv"] == "tab:orange"
    hexes = [to_hex(c) for c in colors.values()]
    assert len(set(hexes)) == 4  # every run its own colour
    builtins = run_colors(["np", "mb", "rtv", "fl-nd", "fl", "bound", "oracle1", "oracle2"])
    assert builtins["fl"] == "tab:green" and builtins["oracle2"] == "tab:purple"  # built-ins unchanged
