"""The model benchmark: table, cross-check, failures as results, the `rpbench bench` command."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rpbench.backends import Backend
from rpbench.backends.presets import Preset, SolveOptions
from rpbench.bench import synthetic
from rpbench.bench.runner import RESULT_COLUMNS, BenchSpec, cross_check, format_table, run_benchmark
from rpbench.cli import main
from rpbench.exceptions import ParameterError, SolverError
from rpbench.model import Status, Structure, make_solution
from rpbench.model.instances import save_instance

MODELS = synthetic.suite("tiny", objectives=("weight", "cardinality_then_weight"))


def test_table_has_one_row_per_model_and_preset():
    table = run_benchmark(MODELS, BenchSpec(["highs", "matching"], repeat=2))
    assert list(table.columns) == RESULT_COLUMNS and len(table) == 2 * len(MODELS)
    assert (table["status"] == "optimal").all() and table["agrees"].all()
    assert (table["build_s"] >= 0).all() and (table["solve_s"] >= 0).all() and (table["repeats"] == 2).all()
    assert table["model"].tolist()[:2] == [MODELS[0].name] * 2  # grouped by model
    text = format_table(table)
    assert "matching" in text and "yes" in text and "NO" not in text


@pytest.mark.slow
def test_isolated_workers_give_the_same_answers():
    inline = run_benchmark(MODELS[:2], BenchSpec(["matching"]))
    isolated = run_benchmark(MODELS[:2], BenchSpec(["matching"], isolate=True))
    assert inline["objective"].tolist() == isolated["objective"].tolist()


def test_cross_check_flags_disagreement_and_impossible_values():
    rows = [
        ("m", "optimal", 5.0),
        ("m", "optimal", 4.0),
        ("n", "optimal", 5.0),
        ("n", "time_limit", 6.0),
        ("n", "time_limit", 3.0),
        ("n", "error", np.nan),
    ]
    rows = [dict(zip(("model", "status", "objective"), r, strict=True)) for r in rows]
    agrees = cross_check(pd.DataFrame(rows))["agrees"].tolist()
    assert agrees[:4] == [False, False, True, False] and pd.isna(agrees[4]) and pd.isna(agrees[5])


class _Broken(Backend):
    name, requires, exact, description = "broken", (), frozenset(Structure), "returns x = 0 as 'optimal'"

    def solve(self, model, options):
        if model.n_cols > 5 and model.structure is Structure.PAIRING:
            raise SolverError("broken on purpose")
        return make_solution(model, [], Status.OPTIMAL, self.name)


def test_errors_and_wrong_answers_are_rows_not_crashes(monkeypatch):
    preset = Preset(name="broken", backend="highs", description="", options=SolveOptions(), path="-")
    monkeypatch.setattr(
        Preset,
        "adapter",
        lambda self: (
            _Broken()
            if self.name == "broken"
            else __import__("rpbench.backends", fromlist=["get_backend"]).get_backend(self.backend)
        ),
    )
    table = run_benchmark(MODELS[1:3], BenchSpec(["matching", preset]))
    broken = table[table["preset"] == "broken"]
    assert broken["status"].tolist() == ["error", "error"] and "broken on purpose" in broken["message"].iloc[0]


@pytest.mark.slow
def test_time_limit_is_a_result():
    model = synthetic.pairing(1500, partners=30)
    table = run_benchmark([model], BenchSpec(["highs"], time_limit_s=0.3))
    assert table["status"].iloc[0] == "time_limit" and pd.isna(table["agrees"].iloc[0])


def test_bad_repeat():
    with pytest.raises(ParameterError, match="repeat"):
        run_benchmark(MODELS, BenchSpec(["highs"], repeat=0))


def test_bench_command_json(capsys, tmp_path):
    csv = tmp_path / "bench.csv"
    code = main(
        [
            "bench",
            "--synthetic",
            "--sizes",
            "tiny",
            "--solver",
            "matching",
            "--solver",
            "scipy",
            "--repeat",
            "1",
            "--no-isolate",
            "--json",
            "--csv",
            str(csv),
            "--objectives",
            "weight,cardinality_then_weight",
            "--preset-time-limit",
            "scipy=20",
        ]
    )
    assert code == 0
    records = json.loads(capsys.readouterr().out)
    assert len(records) == 8 and {r["status"] for r in records} == {"optimal"} and csv.exists()


@pytest.mark.parametrize(
    "argv, match",
    [
        (["bench"], "pass --synthetic"),
        (["bench", "no/such/folder"], "does not exist"),
        (["bench", "--synthetic", "--structures", "assignment,knapsack"], "--structures"),
        (["bench", "--synthetic", "--objectives", "max"], "--objectives"),
        (["bench", "--synthetic", "--preset-time-limit", "highs"], "NAME=SECONDS"),
        (["bench", "--synthetic", "--time-limit", "0"], "--time-limit 0 is out of range"),
        (["bench", "--synthetic", "--sizes", "tiny", "--solver", "nope"], "unknown solver preset"),
    ],
)
def test_bench_command_errors(argv, match, capsys):
    assert main(argv) == 2
    assert match in capsys.readouterr().err


EXAMPLES = Path(__file__).resolve().parents[2] / "instances" / "examples"


@pytest.mark.slow
def test_bench_command_on_the_committed_example_instances(capsys):
    code = main(
        ["bench", str(EXAMPLES), "--solver", "matching", "--solver", "highs", "--repeat", "1", "--no-isolate", "--json"]
    )
    records = json.loads(capsys.readouterr().out)
    assert code == 0
    files = sorted(p.stem for p in EXAMPLES.glob("*.npz"))
    assert sorted({r["model"] for r in records}) == files and len(records) == 2 * len(files)
    assert all(r["agrees"] is True for r in records)
    frozen = [r for r in records if r["model"].startswith("toy_")]
    assert frozen and all(r["recorded"] == r["objective"] for r in frozen)


def test_a_recorded_optimum_the_solvers_do_not_reach_is_flagged(tmp_path, capsys):
    model = synthetic.assignment(6, 10, seed=3)
    best = run_benchmark([model], BenchSpec(["matching"]))["objective"][0]
    save_instance(tmp_path / "a.npz", model, {"status": "optimal", "objective": best + 1})
    save_instance(tmp_path / "sub" / "a.npz", model, {"status": "optimal", "objective": best})
    assert main(["bench", str(tmp_path), "--solver", "matching", "--repeat", "1", "--no-isolate", "--json"]) == 1
    records = {r["model"]: r for r in json.loads(capsys.readouterr().out)}
    assert records[f"{tmp_path.name}/a"]["agrees"] is False and records["sub/a"]["agrees"] is True


def test_bench_structures_filter(capsys):
    assert (
        main(
            [
                "bench",
                "--synthetic",
                "--sizes",
                "tiny",
                "--structures",
                "pairing",
                "--solver",
                "matching",
                "--repeat",
                "1",
                "--no-isolate",
                "--json",
            ]
        )
        == 0
    )
    assert {r["structure"] for r in json.loads(capsys.readouterr().out)} == {"pairing"}


def test_bench_plot(tmp_path):
    png = tmp_path / "bench.png"
    assert (
        main(
            [
                "bench",
                "--synthetic",
                "--sizes",
                "tiny",
                "--solver",
                "matching",
                "--solver",
                "scipy",
                "--repeat",
                "1",
                "--no-isolate",
                "--plot",
                str(png),
            ]
        )
        == 0
    )
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_bad_structures_fail_before_the_synthetic_suite_is_built(monkeypatch, capsys):
    def never(*args, **kwargs):
        raise AssertionError("the synthetic suite was built before --structures was checked")

    monkeypatch.setattr("rpbench.commands.bench.suite", never)
    assert main(["bench", "--synthetic", "--structures", "knapsack"]) == 2
    assert "--structures 'knapsack'" in capsys.readouterr().err
