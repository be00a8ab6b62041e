"""What the harness returns: the facts it knew when it wrote a folder are the facts its files say."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from faults.test_runs_helpers import preset_file

from rpbench.exceptions import ResultsError
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


def test_an_outcome_reads_at_a_python_prompt():
    """The repr gives the folder, each run's saving, the bracket (LB from the best simulated run, U from the
    bound) and the runs to be careful with; ``savings`` and ``bracket`` are the same numbers."""
    table = pd.DataFrame({"mb": [300.0], "fl": [350.0], "bound": [500.0]}, index=["total_saving_km"])
    outcome = Outcome(Path("runs/a"), table, {"fl": "2 of 360 rounds stopped at the time limit"})
    assert outcome.savings.to_dict() == {"mb": 300.0, "fl": 350.0, "bound": 500.0}
    assert outcome.bracket == (350.0, "fl", 500.0)
    text = repr(outcome)
    assert text.startswith("Outcome('runs/a')") and "saving (km): MB 300.0, FL 350.0, Upper bound 500.0" in text
    assert "OPT in [LB, U]: LB = 350.0 (FL), U = 500.0" in text
    assert "FL unproven: 2 of 360 rounds stopped at the time limit" in text
    unbounded = Outcome(Path("b"), table[["mb"]])
    assert unbounded.bracket == (300.0, "mb", None) and "no upper bound run" in repr(unbounded)
    assert Outcome(Path("c"), pd.DataFrame()).bracket is None and "saving (km)" not in repr(
        Outcome(Path("c"), pd.DataFrame())
    )


def test_called_twice_from_python_each_call_gets_a_folder_and_errors_name_out(tmp_path, monkeypatch):
    """Without ``out`` every call writes a new folder under ./rpbench-runs; an ``out`` that exists is refused
    naming the Python parameter (``out=``), not the command line's ``--out``."""
    monkeypatch.chdir(tmp_path)
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1), ["mb"])
    first, second = (run_comparison(spec, progress=False) for _ in range(2))
    assert first.folder != second.folder and first.folder.parent == second.folder.parent == tmp_path / "rpbench-runs"
    with pytest.raises(ResultsError) as info:
        run_comparison(spec, first.folder, progress=False)
    assert str(info.value).startswith(f"out={str(first.folder)!r} already exists (a folder)")
    assert "--out" not in str(info.value) and "pass another out=" in str(info.value)
