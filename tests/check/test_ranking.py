"""An evaluation ranks a clairvoyant run apart, after the online runs: leaderboard.csv records the ranking and
``rpbench check`` fails ``ranking`` when a clairvoyant run is ranked among the online ones."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from check.tamper import assert_passes, copy, edit_csv, violations
from rpbench.report.evaluation import write_evaluation_tables


@pytest.fixture
def ranked_copy(ranked, tmp_path):
    return copy(ranked, tmp_path)


def ranking(folder) -> dict[str, tuple[str, int]]:
    board = pd.read_csv(folder / "leaderboard.csv").drop_duplicates("run").set_index("run")
    return {str(r): (str(g), int(k)) for r, g, k in zip(board.index, board["group"], board["rank"], strict=True)}


def test_the_clairvoyant_run_is_ranked_after_the_online_ones(ranked):
    assert_passes(ranked)
    assert ranking(ranked) == {"mb": ("online", 1), "hindsight": ("clairvoyant", 2), "bound": ("offline", 3)}
    board = pd.read_csv(ranked / "leaderboard.csv").set_index(["run", "kpi"])["mean"]
    assert board[("hindsight", "total_saving_km")] > board[("mb", "total_saving_km")]  # it saved more, yet ranks 2
    assert "| online 1 | MB |" in (ranked / "report.md").read_text()


def test_a_clairvoyant_run_moved_among_the_online_runs_fails(ranked_copy):
    def promote(t):
        t.loc[t["run"] == "hindsight", ["group", "rank"]] = ["online", 1]
        t.loc[t["run"] == "mb", "rank"] = 2

    edit_csv(ranked_copy / "leaderboard.csv", promote)
    messages = " ".join(violations(ranked_copy)["ranking"])
    assert "puts hindsight among the online runs" in messages and "make it clairvoyant" in messages


def test_a_clairvoyant_run_ranked_above_an_online_one_fails(ranked_copy):
    """Only the ranks edited, the groups kept: the file contradicts itself."""

    def swap(t):
        t.loc[t["run"] == "hindsight", "rank"] = 1
        t.loc[t["run"] == "mb", "rank"] = 2

    edit_csv(ranked_copy / "leaderboard.csv", swap)
    messages = " ".join(violations(ranked_copy)["ranking"])
    assert "clairvoyant run hindsight is ranked 1, above the online run mb" in messages


def test_flags_edited_to_online_neither_move_the_run_nor_pass(ranked_copy):
    """Every unit's flag edited to false, the tables rewritten: the strategy's class still ranks it apart, and
    each unit fails ``clairvoyant``; a leaderboard ranking it by the edited flags fails ``ranking``."""
    for unit in ("seed0", "seed1"):
        meta = json.loads((ranked_copy / unit / "meta.json").read_text())
        meta["runs"]["hindsight"]["clairvoyant"] = False
        (ranked_copy / unit / "meta.json").write_text(json.dumps(meta))
    write_evaluation_tables(ranked_copy)
    assert ranking(ranked_copy)["hindsight"] == ("clairvoyant", 2)
    found = violations(ranked_copy)
    assert set(found) <= {"clairvoyant", "report", "report-html"} and len(found["clairvoyant"]) == 2, found

    def by_flags(t):  # what a ranking trusting the flags alone would write
        t.loc[t["run"] == "hindsight", ["group", "rank"]] = ["online", 1]
        t.loc[t["run"] == "mb", "rank"] = 2

    edit_csv(ranked_copy / "leaderboard.csv", by_flags)
    assert "ranking" in violations(ranked_copy)


def test_a_leaderboard_of_an_older_rpbench_has_no_ranking_to_check(ranked_copy):
    edit_csv(ranked_copy / "leaderboard.csv", lambda t: t.drop(columns=["group", "rank"]))
    (parent, *_) = assert_passes(ranked_copy)
    assert "records no ranking" in parent.folder_check.skipped["ranking"]
