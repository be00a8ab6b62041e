"""``rpbench evaluate``: a protocol's units run once, an interrupted evaluation resumes to the same tables,
and the checker recomputes the leaderboard from the units."""

from __future__ import annotations

import os
import shutil

import pandas as pd
import pytest

from rpbench.check import check_tree
from rpbench.cli import main
from rpbench.exceptions import ParameterError
from rpbench.harness.evaluate import run_evaluation
from rpbench.protocols import load_protocol
from rpbench.report.comparison import fmt
from rpbench.results.metrics import TIMING_KPIS
from rpbench.results.store import read_meta

PROTOCOL = """
name = "toy-test"
version = 1
description = "a tiny toy protocol"
scenario = "toy"
sample = 0.1
seeds = [0, 1, 2]
strategies = ["mb", "fl", "bound"]
metrics = ["total_saving_km", "competitive_ratio_bound", "pairing_ratio"]
[bootstrap]
resamples = 200
seed = 3
level = 0.9
"""


def units_run(outcome) -> int:
    """How many units an evaluation ran now (the others were found in its folder)."""
    return sum(unit.fresh for unit in outcome.children)


def folder_and_ran(outcome):
    return outcome.folder, units_run(outcome)


@pytest.fixture(scope="module")
def protocol(tmp_path_factory):
    path = tmp_path_factory.mktemp("protocol") / "toy-test.toml"
    path.write_text(PROTOCOL)
    return load_protocol(str(path))


@pytest.fixture(scope="module")
def evaluated(protocol, tmp_path_factory):
    folder, ran = folder_and_ran(run_evaluation(protocol, tmp_path_factory.mktemp("eval") / "whole", workers=1))
    assert ran == 3
    return folder


def without_timing(path):
    table = pd.read_csv(path)
    return table[~table["kpi"].isin(TIMING_KPIS)].reset_index(drop=True)


def test_an_evaluation_folder(evaluated):
    assert sorted(p.name for p in evaluated.iterdir() if p.is_dir()) == ["seed0", "seed1", "seed2"]
    board = pd.read_csv(evaluated / "leaderboard.csv").set_index(["run", "kpi"])
    assert ("bound", "competitive_ratio_bound") not in board.index  # the bound has no ratio of its own
    assert ("fl", "competitive_ratio_best_known") in board.index  # the interval's other end, beside the ratio
    ranks = board.reset_index().drop_duplicates("run").set_index("run")
    assert ranks["group"].to_dict() == {"mb": "online", "fl": "online", "bound": "offline"}
    assert ranks.loc["bound", "rank"] == 3  # a reference, after the strategies
    assert (board["ci_low"] <= board["mean"] + 1e-12).all() and (board["mean"] <= board["ci_high"] + 1e-12).all()
    assert ("fl", "saving_ratio_of_means") in board.index and (board["seeds"] == 1).all()  # undated: seeds cluster
    pairs = pd.read_csv(evaluated / "paired.csv")
    assert set(zip(pairs["a"], pairs["b"], strict=True)) == {("mb", "fl")}  # online runs only
    report = (evaluated / "report.md").read_text()
    assert "## Leaderboard" in report and "Wilcoxon" in report and "ratio of means" in report
    assert "fig-leaderboard" in (evaluated / "report.html").read_text()
    for figure in ("leaderboard", "by_day_total_saving_km"):  # intervals and the seeds' spread, drawn
        assert f"]({figure}.png)" in report
        assert (evaluated / f"{figure}.png").is_file() and not (evaluated / f"{figure}.svg").exists()  # PNG only
    tex = (evaluated / "table.tex").read_text()
    assert "\\toprule" in tex and tex.count("\\\\") == 1 + 3  # a header and a row per run
    fl = board.loc[("fl", "total_saving_km")]
    cell = " [".join([fmt("total_saving_km", fl["mean"]), fmt("total_saving_km", fl["ci_low"])])
    assert f"{cell}, {fmt('total_saving_km', fl['ci_high'])}]" in tex  # the report's cell, as printed
    assert all(r.status == "ok" for r in check_tree(evaluated))


def test_a_published_evaluation_keeps_its_units_light(evaluated, tmp_path):
    """The units of a published evaluation keep their tables and report, not their figures nor page; the
    evaluation's page links their reports instead, and its tables still check against them."""
    from rpbench.harness.publish import publish

    dest = publish(evaluated, tmp_path / "published")
    for unit in ("seed0", "seed1", "seed2"):
        kept = {p.name for p in (dest / unit).iterdir()}
        assert {"kpis.csv", "meta.json", "report.md", "check.txt", "table.tex"} <= kept
        assert not kept & {"report.html", "kpis.png", "kpis.svg", "timeline.png"}
        assert "unit of a published evaluation" in (dest / unit / "report.md").read_text()
    page = (dest / "report.html").read_text()
    assert 'href="seed0/report.md"' in page and 'href="seed0/report.html"' not in page
    assert (dest / "leaderboard.png").is_file() and (dest / "table.tex").is_file()
    (parent, *_) = check_tree(dest)
    assert parent.status == "ok" and parent.folder_check.checked["leaderboard"] > 0


def test_an_interrupted_evaluation_resumes_to_the_same_tables(protocol, evaluated, tmp_path):
    folder = tmp_path / "resumed"
    shutil.copytree(evaluated, folder)
    shutil.rmtree(folder / "seed1")  # units are written whole or not at all: an interruption loses whole units
    stale = folder / ".seed1.partial-999999999"  # and may leave a dead process's partial folder
    stale.mkdir()
    os.utime(stale, (0, 0))  # old: a folder of a live run is never swept
    for name in ("units.csv", "leaderboard.csv", "paired.csv"):
        (folder / name).unlink()
    again, ran = folder_and_ran(run_evaluation(protocol, folder, workers=1))
    assert ran == 1 and not (folder / ".seed1.partial-999999999").exists()
    for name in ("leaderboard.csv", "paired.csv"):
        assert (again / name).read_bytes() == (evaluated / name).read_bytes()
    pd.testing.assert_frame_equal(without_timing(again / "units.csv"), without_timing(evaluated / "units.csv"))
    assert units_run(run_evaluation(protocol, folder, workers=1)) == 0  # complete: nothing reruns


def test_another_protocol_does_not_resume_a_folder(evaluated, tmp_path):
    other = tmp_path / "other.toml"
    other.write_text(PROTOCOL.replace("seeds = [0, 1, 2]", "seeds = [0, 1]"))
    with pytest.raises(ParameterError, match="holds protocol 'toy-test' version 1"):
        run_evaluation(load_protocol(str(other)), evaluated, workers=1)


def test_an_edited_leaderboard_fails_the_check(evaluated, tmp_path):
    folder = tmp_path / "edited"
    shutil.copytree(evaluated, folder)
    board = pd.read_csv(folder / "leaderboard.csv")
    board.loc[(board["run"] == "fl") & (board["kpi"] == "total_saving_km"), "ci_high"] *= 1.5
    board.to_csv(folder / "leaderboard.csv", index=False)
    (parent, *_) = check_tree(folder)
    assert "parent-tables" in parent.folder_check.violations
    assert any("leaderboard.csv: ci_high of ('fl', 'total_saving_km')" in m
               for m in parent.folder_check.violations["parent-tables"])  # fmt: skip


def test_bad_input_is_one_line(capsys, tmp_path):
    assert main(["evaluate", "no-such-protocol"]) == 2
    assert "unknown protocol 'no-such-protocol'" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["evaluate", "toy-quick", "--out", str(tmp_path / "file")]) == 2


def test_another_decision_budget_does_not_resume_a_folder(protocol, evaluated):
    """Every unit's rounds_over_budget counts against the one budget the evaluation records (none here)."""
    with pytest.raises(ParameterError, match="evaluated with no decision budget, not a decision budget of 0.5 s"):
        run_evaluation(protocol, evaluated, workers=1, decision_budget_s=0.5)


def test_an_evaluation_with_a_decision_budget(tmp_path, capsys):
    """Each unit is flagged against the budget the parent records; the tree checks clean; a resume with the
    same budget runs nothing, without one is refused."""
    path = tmp_path / "one.toml"
    text = PROTOCOL.replace("seeds = [0, 1, 2]", "seeds = [0]").replace('"mb", "fl", "bound"', '"mb"')
    path.write_text(text.replace('"competitive_ratio_bound", ', ""))  # no bound run, no ratio over it
    protocol = load_protocol(str(path))
    out = tmp_path / "budget"
    assert main(["evaluate", str(path), "--out", str(out), "--workers", "1", "--decision-budget", "1e-9"]) == 0
    err = capsys.readouterr().err
    assert "rpbench: note: seed0: mb: " in err and "rounds decided slower than the 1e-09 s budget" in err
    assert read_meta(out)["decision_budget_s"] == read_meta(out / "seed0")["decision_budget_s"] == 1e-9
    units = pd.read_csv(out / "units.csv")
    assert (units["kpi"] == "rounds_over_budget").sum() == 1
    assert all(found.status == "ok" for found in check_tree(out))
    assert units_run(run_evaluation(protocol, out, workers=1, decision_budget_s=1e-9)) == 0
    with pytest.raises(ParameterError, match="evaluated with a decision budget of 1e-09 s, not no decision budget"):
        run_evaluation(protocol, out, workers=1)
