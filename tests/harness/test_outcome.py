"""What the harness returns: the facts it knew when it wrote a folder are the facts its files say."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from faults.test_runs_helpers import preset_file

from rpbench.harness.comparison import run_comparison
from rpbench.harness.outcome import Outcome
from rpbench.results.read import load_kpis, over_budget_runs, unproven_runs
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


def test_a_comparison_s_outcome_says_what_its_folder_says(tmp_path, monkeypatch):
    """Unproven rounds and rounds over the budget, known in memory, equal what the folder's files give."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    preset = preset_file(tmp_path, "UnprovenHighs")
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1), ["np", "mb"], preset=preset, decision_budget_s=1e-9)
    outcome = run_comparison(spec, tmp_path / "run", progress=False)
    assert outcome.folder == tmp_path / "run" and outcome.fresh
    assert set(outcome.unproven) == {"np", "mb"} and outcome.unproven == unproven_runs(outcome.folder)
    assert set(outcome.over_budget) == {"np", "mb"} and outcome.over_budget == over_budget_runs(outcome.folder)
    read = load_kpis(outcome.folder)
    pd.testing.assert_frame_equal(outcome.table.loc[read.index, read.columns], read, check_names=False)
    assert Outcome.read(outcome.folder).unproven == outcome.unproven


def test_a_parent_s_remarks_list_unproven_runs_first_then_runs_over_budget():
    day = Outcome(Path("x/2017-05-01"), pd.DataFrame(), {"mb": "1 of 9 rounds"}, {"mb": "2 of 9 rounds"})
    parent = Outcome(Path("x"), pd.DataFrame(), {"bound": "stopped"}, children=(day,))
    assert list(parent.remarks()) == [
        ("", "unproven", "bound", "stopped"),
        ("2017-05-01", "unproven", "mb", "1 of 9 rounds"),
        ("2017-05-01", "over_budget", "mb", "2 of 9 rounds"),
    ]
    assert parent.unproven_runs() == {"bound": "stopped", "mb": "1 of 9 rounds"}
    moved = parent.moved_to(Path("y"))
    assert moved.folder == Path("y") and moved.children[0].folder == Path("y/2017-05-01")
