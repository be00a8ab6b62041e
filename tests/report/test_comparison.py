"""Reports are a pure function of result files: rendered from small hand-written fixture folders."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import pandas as pd
import pytest

from rpbench.exceptions import ResultsError
from rpbench.harness.render import render
from rpbench.report.comparison import check_metrics, fmt, markdown_table, text_table
from rpbench.results.read import load_kpis


def fixture_folder(
    tmp_path, *, scenario="haikou-peak", args=None, runs=("mb", "fl", "oracle1"), hourly=False, name="fixture"
):
    folder = tmp_path / name
    (folder / "runs").mkdir(parents=True)
    for r in runs:
        (folder / "runs" / r).mkdir()
    meta = {
        "scenario": {
            "name": scenario,
            "label": "fixture scenario",
            "synthetic": False,
            "seed": 0,
            "args": args or {"date": "2017-05-01", "sample": 0.3},
            "summary": {"orders": 605, "vehicles": 151, "nodes": 3901},
        },
        "preset": {"name": "highs", "backend": "highs"},
        "strategies": list(runs),
        "versions": {"rpbench": "test"},
        "git_commit": "abc",
        "created": "now",
        "runs": {r: {"wall_s": 1.5} for r in runs},
    }
    (folder / "meta.json").write_text(json.dumps(meta))
    rows = []
    values = {
        "mb": (111.0, 912.0, 0.9),
        "fl": (158.0, 731.0, 0.81),
        "oracle1": (250.0, 942.0, float("nan")),
        "bound": (400.0, 500.0, float("nan")),
    }
    for r, (saving, detour, rr) in ((r, values[r]) for r in runs):
        rows += [
            {"run": r, "kpi": "total_saving_km", "value": saving},
            {"run": r, "kpi": "avg_detour_m", "value": detour},
            {"run": r, "kpi": "response_rate", "value": rr},
        ]
    pd.DataFrame(rows).to_csv(folder / "kpis.csv", index=False)
    if hourly:
        pd.DataFrame(
            [
                {
                    "run": r,
                    "hour": h,
                    "avg_shared_m": 1000 + h,
                    "avg_detour_m": 500,
                    "total_saving_km": h,
                    "response_rate": 0.8,
                }
                for r in runs
                for h in range(24)
            ]
        ).to_csv(folder / "hourly.csv", index=False)
    return folder


def test_table_and_competitive_ratio(tmp_path):
    folder = fixture_folder(tmp_path)
    table = load_kpis(folder)
    assert table.loc["saving_over_oracle1", "fl"] == pytest.approx(158 / 250)
    assert table.loc["competitive_ratio_best_known", "fl"] == 1.0  # FL saved the most: the best known schedule
    assert table.loc["competitive_ratio_best_known", "mb"] == pytest.approx(111 / 158)
    assert pd.isna(table.loc["saving_over_oracle1", "oracle1"])  # an offline run has no ratio
    text = text_table(table)
    assert "Saving / Oracle-1 (paper's reference; not a bound)" in text and "0.632" in text
    assert "saving / proven upper bound" not in text  # no bound in this folder: no ratio against it
    assert "Ratio to the best run here (saving / best saving of these runs)" in text  # no clairvoyant run here
    md, written = render([folder])
    assert "OPT >= LB = 158 km (best known schedule: FL; no upper bound run, so no U)." in md
    assert "reference, not a competitive ratio" in md  # why the Oracle-1 row can exceed 1
    assert written == [folder / "report.md"]
    assert "| Total distance saving due to ride-pooling (km) | 111 | 158 | 250 |" in md
    # the paper's Table 2 is shown beside rpbench's numbers for 2017-05-01 at 30 %
    assert "158 (158)" in md and "0.632 (0.632)" in md


def test_the_competitive_ratio_divides_by_the_bound(tmp_path):
    folder = fixture_folder(tmp_path, runs=("mb", "fl", "bound", "oracle1"))
    table = load_kpis(folder)
    assert table.loc["competitive_ratio_bound", "fl"] == pytest.approx(158 / 400)
    assert table.loc["saving_over_oracle1", "fl"] == pytest.approx(158 / 250)
    assert table.loc["best_known_saving_km", "bound"] == 158.0
    assert table.loc["bound_over_best_known", "bound"] == pytest.approx(400 / 158)
    text = text_table(table)
    rows = [line.split("  ")[0] for line in text.splitlines()]
    assert (
        rows.index("Competitive ratio (saving / proven upper bound)")
        < rows.index("Ratio to the best run here (saving / best saving of these runs)")
        < rows.index("Saving / Oracle-1 (paper's reference; not a bound)")
    )
    md, _ = render([folder])
    assert "| Upper bound |" in md.replace("Upper bound | Oracle-1", "Upper bound |") and "docs/bound.md" in md
    # the bound's column shows only what it bounds, the total saving; its ratios are "/", not 1.000
    assert "| Competitive ratio (saving / proven upper bound) | 0.278 | 0.395 | / | / |" in md
    assert "| Average detour distance (m) | 912 | 731 | / | 942 |" in md
    assert "OPT lies in [LB, U] = [158, 400] km (U / LB = 2.53; best known schedule: FL)." in md
    tex = (folder / "table.tex").read_text()
    assert "OPT lies in [LB, U] = [158, 400] km" in tex


def test_a_metric_under_its_old_name_says_its_new_one():
    with pytest.raises(ResultsError, match="metric 'competitive_ratio' is named 'saving_over_oracle1' now"):
        check_metrics(["competitive_ratio"])
    assert check_metrics(["competitive_ratio_best_known", "saving_over_oracle1"])


def test_the_bound_matching_statistics_of_an_older_folder_are_not_shown(tmp_path):
    """A folder written before rpbench named the bound's matching statistics apart (and called saving /
    Oracle-1 ``competitive_ratio``) reads as today's: the bound's column shows "/" where it bounds nothing."""
    folder = fixture_folder(tmp_path, runs=("mb", "fl", "bound", "oracle1"))
    kpis = pd.read_csv(folder / "kpis.csv")
    legacy = pd.DataFrame([{"run": "fl", "kpi": "competitive_ratio", "value": 0.5}])
    pd.concat([kpis, legacy]).to_csv(folder / "kpis.csv", index=False)
    table = load_kpis(folder)
    assert pd.isna(table.loc["avg_detour_m", "bound"]) and table.loc["matching_avg_detour_m", "bound"] == 500.0
    assert "competitive_ratio" not in table.index  # read as saving_over_oracle1, then recomputed
    assert table.loc["saving_over_oracle1", "fl"] == pytest.approx(158 / 250)


def test_paper_values_only_where_they_apply(tmp_path):
    folder = fixture_folder(tmp_path, args={"date": "2017-05-02", "sample": 0.3})
    md, _ = render([folder])
    assert "Beside the paper" not in md


def test_hourly_plot_for_multi_hour_results(tmp_path):
    folder = fixture_folder(tmp_path, scenario="haikou-day", hourly=True)
    md, _ = render([folder])
    assert (folder / "hourly.png").is_file() and "hourly.png" in md
    assert md.rstrip().endswith("the folder holding this report.")  # the figures come before the last line


def test_every_comparison_has_its_kpi_figure(tmp_path):
    folder = fixture_folder(tmp_path)  # one hour: no per-hour plot, but the KPI bars
    md, _ = render([folder])
    assert (folder / "kpis.png").is_file() and "![headline KPIs per run](kpis.png)" in md
    assert not (folder / "hourly.png").exists() and "without an upper bound run the competitive ratio" in md
    # the runs/ folders hold no event log: the timeline says why it is missing
    assert "No timeline: every run of this folder is offline" in md and not (folder / "timeline.png").exists()


def test_the_check_line_holds_wherever_the_user_stands(tmp_path):
    md, _ = render([fixture_folder(tmp_path, name="peak-2017-05-01")])
    assert "Verify this folder with `rpbench check PATH`, PATH being the path to `peak-2017-05-01`" in md
    assert "rpbench check peak-2017-05-01`" not in md


def test_a_synthetic_scenario_says_so_at_the_top(tmp_path):
    def top(md: str) -> str:
        return md.split("## Comparison")[0]

    folder = fixture_folder(tmp_path, scenario="toy", args={})
    meta = json.loads((folder / "meta.json").read_text())
    meta["scenario"]["synthetic"] = True
    (folder / "meta.json").write_text(json.dumps(meta))
    head = top(render([folder])[0])
    assert "Synthetic city, not Haikou" in head and "`rpbench data fetch`" in head
    meta["scenario"]["name"] = "haikou-day"
    (folder / "meta.json").write_text(json.dumps(meta))
    head = top(render([folder])[0])
    assert "Synthetic orders" in head and "no public full-day order list" in head and "data fetch" not in head
    real = top(render([fixture_folder(tmp_path, name="real")])[0])
    assert "ynthetic" not in real


def test_wall_time_and_one_off_preparation(tmp_path):
    folder = fixture_folder(tmp_path, runs=("mb", "fl"))
    md, _ = render([folder])
    assert "Wall time per run: MB 1.50 s, FL 1.50 s" in md and "preparation" not in md  # no prepare_s: as before
    meta = json.loads((folder / "meta.json").read_text())
    meta["runs"]["mb"]["prepare_s"] = 0.01
    meta["runs"]["fl"]["prepare_s"] = 9.876
    (folder / "meta.json").write_text(json.dumps(meta))
    md, _ = render([folder])
    assert "Wall time of the round loop per run: MB 1.50 s, FL 1.50 s" in md
    line = next(x for x in md.splitlines() if x.startswith("One-off preparation per run"))
    assert "once before its first round" in line and "cache builds included" in line
    assert line.endswith(": FL 9.88 s")  # MB's 0.01 s is below the threshold


def test_selected_metrics_and_unknown_metric(tmp_path):
    folder = fixture_folder(tmp_path)
    md, _ = render([folder], metrics=["response_rate"])
    assert "Response rate" in md and "Average detour" not in md
    md, _ = render([folder, fixture_folder(tmp_path, name="again")], metrics=["response_rate"])  # combined
    assert "Response rate" in md and "Average detour" not in md and "combined comparison" in md
    with pytest.raises(ResultsError, match="unknown metric 'happiness'"):
        render([folder], metrics=["happiness"])


def test_empty_results_folder(tmp_path):
    with pytest.raises(ResultsError, match="not an rpbench results folder"):
        render([tmp_path])
    folder = fixture_folder(tmp_path, runs=())
    (folder / "kpis.csv").unlink()
    with pytest.raises(ResultsError, match="holds no runs"):
        render([folder])


def test_a_light_copy_without_event_logs_still_renders(tmp_path):
    folder = fixture_folder(tmp_path, runs=("mb", "fl", "bound", "oracle1"))
    shutil.rmtree(folder / "runs")
    (folder / "timeline.png").write_bytes(b"drawn from logs this copy no longer holds")
    md, _ = render([folder])
    assert "Competitive ratio (saving / proven upper bound)" in md
    assert (folder / "kpis.png").is_file() and "kpis.png" in md
    assert "No timeline" in md and "light copy leaves out" in md and not (folder / "timeline.png").exists()


def test_report_cli(tmp_path, capsys):
    from rpbench.cli import main

    folder = fixture_folder(tmp_path)
    assert main(["report", str(folder), "--metrics", "nonsense"]) == 2
    assert "unknown metric" in capsys.readouterr().err
    assert main(["report", str(folder)]) == 0
    assert "Comparison" in capsys.readouterr().out


def snapshot(folder: Path) -> dict[str, tuple[int, bytes]]:
    """Every file below ``folder``: modification time and bytes."""
    return {
        str(p.relative_to(folder)): (p.stat().st_mtime_ns, p.read_bytes()) for p in folder.rglob("*") if p.is_file()
    }


def multi_day_folder(tmp_path: Path) -> Path:
    parent = tmp_path / "days"
    for date in ("2017-05-01", "2017-05-02"):
        day = fixture_folder(parent, args={"date": date, "sample": 0.3}, name=date)
        kpis = pd.read_csv(day / "kpis.csv")
        pairing = pd.DataFrame({"run": ["mb", "fl", "oracle1"], "kpi": "pairing_ratio", "value": [0.2, 0.27, 0.66]})
        pd.concat([kpis, pairing]).to_csv(day / "kpis.csv", index=False)  # a KPI the multi-day report tabulates
    meta = {
        "kind": "multi-day",
        "scenario": "haikou-peak",
        "dates": ["2017-05-01", "2017-05-02"],
        "strategies": ["mb", "fl", "oracle1"],
        "seed": 0,
        "preset": "highs",
        "versions": {"rpbench": "test"},
        "git_commit": "abc",
    }
    (parent / "meta.json").write_text(json.dumps(meta))
    return parent


@pytest.mark.parametrize("kind", ["comparison", "multi-day"])
def test_report_out_writes_nothing_in_the_folder(tmp_path, capsys, kind):
    from rpbench.cli import main

    folder = fixture_folder(tmp_path, hourly=True, scenario="haikou-day") if kind == "comparison" else None
    folder = folder or multi_day_folder(tmp_path)
    assert main(["report", str(folder)]) == 0  # a rendered folder, as `rpbench run` leaves it
    before = snapshot(folder)
    time.sleep(0.01)  # a rewrite would show in the modification times, not only in the bytes
    (tmp_path / "out").mkdir()
    out = tmp_path / "out" / "summary.md"
    assert main(["report", str(folder), "--out", str(out)]) == 0
    assert snapshot(folder) == before
    text = out.read_text()
    plots = sorted(p.name for p in out.parent.glob("*.png"))
    assert plots and all(p.startswith("summary-") for p in plots) and "plots beside it" in capsys.readouterr().out
    assert all(f"]({p})" in text for p in plots)  # the links follow the plots
    beside = list(plots)  # PNG only: vector copies on request (--figures)
    if kind == "comparison":
        beside += ["summary-table.tex", "summary-table.csv"]
    assert sorted(out.parent.iterdir()) == sorted([out, *(out.parent / p for p in beside)])  # no leftovers
    assert text == (folder / "report.md").read_text().replace("](", "](summary-")  # what the folder shows


def test_formatting():
    assert fmt("response_rate", 0.8123) == "0.81"
    assert fmt("avg_detour_m", 912.4) == "912"
    assert fmt("total_saving_km", -1e-12) == "0.0"
    assert fmt("competitive_ratio_bound", -1e-9) == "0.000"
    assert fmt("saving_over_oracle1", 1.5) == "1.500" and fmt("bound_over_best_known", 1.0498) == "1.05"
    assert fmt("avg_detour_m", float("nan")) == "/"


def test_a_failed_report_out_leaves_no_plots_behind(tmp_path, capsys, monkeypatch):
    from rpbench.cli import main

    folder = fixture_folder(tmp_path)
    (tmp_path / "out").mkdir()
    out = tmp_path / "out" / "r.md"
    real_write_text = Path.write_text

    def full_disk(self, *args, **kwargs):  # the markdown, written last, finds the disk full
        if self.parent == out.parent:
            raise OSError(28, "No space left on device")
        return real_write_text(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", full_disk)
    assert main(["report", str(folder), "--out", str(out)]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert list(out.parent.iterdir()) == []


def test_without_a_clairvoyant_run_the_best_known_ratio_says_it_is_relative_to_these_runs():
    """LB is the best run shown: with only online runs that run's 1.000 means "best here", and the row says so;
    with Hindsight (clairvoyant) it is the best known schedule."""
    table = pd.DataFrame(
        {"mb": [300.0, 0.6, 0.75], "fl": [400.0, 0.8, 1.0], "bound": [500.0, float("nan"), float("nan")]},
        index=["total_saving_km", "competitive_ratio_bound", "competitive_ratio_best_known"],
    )
    online = text_table(table)
    assert "Ratio to the best run here (saving / best saving of these runs)" in online
    assert "Competitive ratio (saving / best known schedule)" not in online
    with_hindsight = table.assign(hindsight=[450.0, 0.9, 1.0])
    assert "Competitive ratio (saving / best known schedule)" in text_table(with_hindsight)
    assert "best run here" not in markdown_table(with_hindsight) and "best run here" in markdown_table(table)
