"""A run that read the future is labelled so wherever it is shown, and ranked apart from the online runs."""

from __future__ import annotations

import pandas as pd

from rpbench.report.evaluation import leaderboard_rows
from rpbench.results.ranking import ranked, run_groups
from rpbench.results.runs import CLAIRVOYANT_MARK, clairvoyant_runs, run_label, run_styles

META = {
    "runs": {
        "mb": {"kind": "simulation", "label": "MB", "color": "tab:blue", "clairvoyant": False},
        "fl": {"kind": "simulation", "label": "FL", "color": "tab:green", "clairvoyant": True},
        "old": {"kind": "simulation", "label": "Old", "color": None},  # written before runs recorded it
        "bound": {"kind": "oracle", "label": "Upper bound", "color": "black"},
    }
}


def test_a_clairvoyant_run_is_marked_in_its_label():
    styles = run_styles(META)
    assert clairvoyant_runs(META) == {"fl"}
    assert styles["fl"] == ("FL (clairvoyant)", "tab:green") and CLAIRVOYANT_MARK == " (clairvoyant)"
    assert [run_label(r, styles) for r in ("mb", "old", "bound")] == ["MB", "Old", "Upper bound"]


def test_a_class_declaring_clairvoyance_is_marked_without_a_record(monkeypatch):
    from rpbench import results
    from rpbench.strategies.myopic import MyopicBatch

    class Seer(MyopicBatch):
        label = "Seer"
        clairvoyant = True

    monkeypatch.setattr(results.runs, "strategy_class", lambda name: Seer if name == "seer" else MyopicBatch)
    assert run_label("seer") == "Seer (clairvoyant)"
    assert run_label("mb") == "MB"  # a property (FL's, MB's default) does not mark a class


def test_the_leaderboard_ranks_clairvoyant_runs_apart():
    """FL read the future and saved the most: it is ranked after the online runs, not first."""
    board = pd.DataFrame(
        [
            {"run": r, "kpi": "total_saving_km", "mean": m, "ci_low": m, "ci_high": m, "days": 1, "seeds": 1}
            for r, m in (("mb", 5.0), ("fl", 9.0), ("old", 7.0))
        ]
    )
    runs = ["mb", "fl", "old"]
    protocol = {"metrics": ["total_saving_km"], "strategies": runs}
    styles = run_styles(META)
    groups = run_groups([META["runs"]], runs)
    assert groups == {"mb": "online", "fl": "clairvoyant", "old": "online"}
    _, body = leaderboard_rows(ranked(board, groups, "total_saving_km", runs), protocol, styles)
    assert [row[:2] for row in body] == [["online 1", "Old"], ["online 2", "MB"], ["clairvoyant 1", "FL (clairvoyant)"]]
    online = dict.fromkeys(runs, "online")
    _, mixed = leaderboard_rows(ranked(board, online, "total_saving_km", runs), protocol, styles)
    assert [row[1] for row in mixed] == ["FL (clairvoyant)", "Old", "MB"]  # by the metric alone
