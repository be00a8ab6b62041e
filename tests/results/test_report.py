"""Reports are a pure function of result files: rendered from small hand-written fixture folders."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest

from rpbench.exceptions import ResultsError
from rpbench.harness.render import render
from rpbench.results.report import fmt, load_kpis, text_table


def fixture_folder(tmp_path, *, scenario="haikou-peak", args=None, runs=("mb", "fl", "oracle1"), hourly=False):
    folder = tmp_path / "fixture"
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
    assert table.loc["competitive_ratio", "fl"] == pytest.approx(158 / 250)
    text = text_table(table)
    assert "Saving / Oracle-1 (paper: same-window pairs; not a bound)" in text and "0.632" in text
    assert "Competitive ratio" not in text  # no bound in this folder: no competitive ratio
    md, written = render([folder])
    assert "a reference, not a competitive ratio" in md  # why the Oracle-1 row can exceed 1
    assert written == [folder / "report.md"]
    assert "| Total distance saving due to ride-pooling (km) | 111 | 158 | 250 |" in md
    # the paper's Table 2 is shown beside rpbench's numbers for 2017-05-01 at 30 %
    assert "158 (158)" in md and "0.632 (0.632)" in md


def test_the_competitive_ratio_divides_by_the_bound(tmp_path):
    folder = fixture_folder(tmp_path, runs=("mb", "fl", "bound", "oracle1"))
    table = load_kpis(folder)
    assert table.loc["competitive_ratio_bound", "fl"] == pytest.approx(158 / 400)
    assert table.loc["competitive_ratio", "fl"] == pytest.approx(158 / 250)
    text = text_table(table)
    rows = [line.split("  ")[0] for line in text.splitlines()]
    assert rows.index("Competitive ratio (saving / proven upper bound)") < rows.index(
        "Saving / Oracle-1 (paper: same-window pairs; not a bound)"
    )
    md, _ = render([folder])
    assert "| Upper bound |" in md.replace("Upper bound | Oracle-1", "Upper bound |") and "docs/bound.md" in md


def test_paper_values_only_where_they_apply(tmp_path):
    folder = fixture_folder(tmp_path, args={"date": "2017-05-02", "sample": 0.3})
    md, _ = render([folder])
    assert "Beside the paper" not in md


def test_hourly_plot_for_multi_hour_results(tmp_path):
    folder = fixture_folder(tmp_path, scenario="haikou-day", hourly=True)
    md, _ = render([folder])
    assert (folder / "hourly.png").is_file() and "hourly.png" in md


def test_selected_metrics_and_unknown_metric(tmp_path):
    folder = fixture_folder(tmp_path)
    md, _ = render([folder, folder], metrics=["response_rate"])
    assert "Response rate" in md and "Average detour" not in md
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
    md, _ = render([folder])
    assert "Competitive ratio (saving / proven upper bound)" in md


def test_report_cli(tmp_path, capsys):
    from rpbench.cli import main

    folder = fixture_folder(tmp_path)
    assert main(["report", str(folder), "--metrics", "nonsense"]) == 2
    assert "unknown metric" in capsys.readouterr().err
    assert main(["report", str(folder)]) == 0
    assert "Comparison" in capsys.readouterr().out


def test_formatting():
    assert fmt("response_rate", 0.8123) == "0.81"
    assert fmt("avg_detour_m", 912.4) == "912"
    assert fmt("total_saving_km", -1e-12) == "0.0"
    assert fmt("competitive_ratio", -1e-9) == "0.000"
    assert fmt("avg_detour_m", float("nan")) == "/"
