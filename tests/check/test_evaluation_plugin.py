"""A run the units hold cannot drop out of an evaluation's leaderboard: a ``module:Class`` plug-in listed in a
protocol runs under its class's name, and a leaderboard ranking the protocol's text instead (what rpbench
wrote before it ranked the units' runs) fails ``leaderboard-runs`` wherever the run is missing."""

from __future__ import annotations

import sys

import pytest
from plugin_helpers import EXAMPLE, forget

from check.tamper import assert_passes, copy, violations
from rpbench import results
from rpbench.harness.evaluate import run_evaluation
from rpbench.protocols import load_protocol
from rpbench.report.evaluation import (
    board_metrics,
    bootstrap_of,
    evaluation_report,
    unit_records,
    units_table,
)
from rpbench.report.html import write_html
from rpbench.report.leaderboard import leaderboard, paired
from rpbench.results.ranking import ranked, run_groups

pytestmark = pytest.mark.slow
PLUGIN = "rpbench_greedy.strategy:GreedyPickup"
PROTOCOL = f"""
name = "plug-in"
version = 1
scenario = "toy"
sample = 0.1
seeds = [0, 1]
strategies = ["mb", "{PLUGIN}", "bound"]
oracle_preset = "matching"
metrics = ["total_saving_km", "competitive_ratio_bound"]
[bootstrap]
resamples = 100
"""


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    path = tmp_path_factory.mktemp("protocol") / "plug-in.toml"
    path.write_text(PROTOCOL)
    sys.path.insert(0, str(EXAMPLE))
    try:
        return run_evaluation(load_protocol(str(path)), tmp_path_factory.mktemp("eval") / "plug-in", workers=1).folder
    finally:
        sys.path.remove(str(EXAMPLE))
        forget("rpbench_greedy")


def rank_the_protocols_text(folder) -> None:
    """Rewrite the tables, report and page ranking the protocol's entries as written, with rpbench's own
    functions: the plug-in's rows are then missing (its units name it ``greedy``)."""
    meta = results.read_meta(folder)
    protocol = meta["protocol"]
    runs, metrics, boot = list(protocol["strategies"]), list(protocol["metrics"]), bootstrap_of(meta)
    units = units_table(folder)
    units["day"] = units["day"].fillna("").astype(str)
    groups = run_groups(unit_records(folder), runs)
    board = ranked(leaderboard(units, runs, board_metrics(metrics), boot), groups, metrics[0], runs)
    pairs = paired(units, [r for r in runs if groups[r] != "offline"], metrics, boot)
    board.to_csv(folder / "leaderboard.csv", index=False)
    pairs.to_csv(folder / "paired.csv", index=False)
    report = evaluation_report(folder, folder.name, board, pairs, units, runs)
    (folder / "report.md").write_text(report.markdown)
    (folder / "table.tex").write_text(report.tex)
    write_html(folder, folder.name)


def test_the_plug_in_is_ranked_under_the_name_its_units_give_it(evaluated):
    (parent, *_) = assert_passes(evaluated)
    board = results.read_csv(evaluated / "leaderboard.csv")
    assert "greedy" in set(board["run"]) and PLUGIN not in set(board["run"])
    assert parent.folder_check.checked["held_runs"] == 3
    assert any("options of a plug-in" in reason for reason in parent.folder_check.skipped.values())


def test_a_leaderboard_leaving_out_the_plug_in_fails(evaluated, tmp_path):
    folder = copy(evaluated, tmp_path)
    rank_the_protocols_text(folder)
    found = " ".join(violations(folder)["leaderboard-runs"])
    for where in (
        "leaderboard.csv leaves out run 'greedy'",
        "paired.csv has no test of 'greedy' against 'mb'",
        "report.md's leaderboard shows no value of run 'greedy'",
        "table.tex's leaderboard shows no value of run 'greedy'",
        "report.html's leaderboard figure leaves out run 'greedy'",
    ):
        assert where in found, where
