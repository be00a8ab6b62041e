"""Verdicts of benchmark rows: known values (.solu) and the other presets decide ``wrong``; time and memory
limits, errors and killed workers are verdicts too; a wrong answer is exit status 1."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from rpbench.backends.presets import Preset
from rpbench.bench import synthetic
from rpbench.bench.runner import BenchSpec, cross_check, run_benchmark, verdict
from rpbench.cli import main
from rpbench.model.instances import save_instance
from rpbench.report.bench import summarise
from rpbench.results.solu import Known, write_solu

OPT, TL, FEAS, INF = "optimal", "time_limit", "feasible", "infeasible"


@pytest.mark.parametrize(
    "status, objective, peers, known, expected",
    [
        # the .solu optimum decides
        (OPT, 10.0, [], Known("opt", 10.0), "optimal"),
        (OPT, 9.0, [], Known("opt", 10.0), "wrong"),
        (OPT, 10.0, [9.0], Known("opt", 10.0), "optimal"),  # the other preset is the wrong one
        (TL, 9.0, [], Known("opt", 10.0), "time_limit"),
        (TL, 11.0, [], Known("opt", 10.0), "wrong"),  # more than the optimum
        (FEAS, 9.0, [], Known("opt", 10.0), "feasible"),
        # best known (feasible) and bound
        (OPT, 12.0, [], Known("best", 10.0), "optimal"),
        (OPT, 9.0, [], Known("best", 10.0), "wrong"),
        (TL, 9.0, [], Known("best", 10.0), "time_limit"),
        (OPT, 10.0, [], Known("bound", 10.0), "optimal"),
        (TL, 11.0, [], Known("bound", 10.0), "wrong"),
        # infeasibility
        (INF, math.nan, [], Known("inf"), "optimal"),
        (OPT, 5.0, [], Known("inf"), "wrong"),
        (INF, math.nan, [], Known("opt", 3.0), "wrong"),
        (INF, math.nan, [3.0], None, "wrong"),
        (INF, math.nan, [], None, "infeasible"),
        # no known value: the other presets' proven optima
        (OPT, 10.0, [10.0, 10.0], None, "optimal"),
        (OPT, 10.0, [11.0], None, "wrong"),
        (OPT, 10.0, [], Known("unkn"), "optimal"),
        (TL, 9.0, [10.0], None, "time_limit"),
        (TL, 11.0, [10.0], None, "wrong"),
        (TL, 11.0, [10.0, 12.0], None, "time_limit"),  # not above every proven optimum
        # failures are verdicts of their own, whatever is known
        ("error", math.nan, [10.0], Known("opt", 10.0), "error"),
        ("killed", math.nan, [], None, "killed"),
        ("memory_limit", math.nan, [], None, "memory_limit"),
    ],
)
def test_verdict(status, objective, peers, known, expected):
    assert verdict(status, objective, peers, known) == expected


def test_cross_check_uses_the_known_values_by_model_name():
    rows = [("m", OPT, 5.0), ("m", OPT, 4.0), ("n", OPT, 5.0), ("n", OPT, 4.0)]
    table = pd.DataFrame([dict(zip(("model", "status", "objective"), r, strict=True)) for r in rows])
    out = cross_check(table, {"m": Known("opt", 5.0)})
    assert out["verdict"].tolist() == ["optimal", "wrong", "wrong", "wrong"]  # n: nothing tells which is right
    assert out["agrees"].tolist() == [False] * 4  # agrees keeps its meaning: the optima differ


@pytest.fixture(scope="module")
def instance_folder(tmp_path_factory):
    """Two instance files, one of tier S and one without a tier, and their optima."""
    folder = tmp_path_factory.mktemp("instances")
    a, b = synthetic.assignment(6, 10, seed=3), synthetic.pairing(40, partners=5, seed=2)
    save_instance(folder / "a.npz", a, {"tier": "S"})
    save_instance(folder / "b.npz", b, {})
    optima = run_benchmark([a.renamed("a"), b.renamed("b")], BenchSpec(["matching"]))["objective"].tolist()
    return folder, optima


BENCH = ["--solver", "matching", "--solver", "highs", "--repeat", "1", "--no-isolate"]


def test_a_wrong_known_optimum_gives_verdict_wrong_and_exit_1(instance_folder, tmp_path, capsys):
    folder, (opt_a, opt_b) = instance_folder
    solu = tmp_path / "set.solu"
    write_solu(solu, {"a": Known("opt", opt_a + 1), "b": Known("opt", opt_b)}, [])
    assert main(["bench", str(folder), "--solu", str(solu), *BENCH, "--json"]) == 1
    out, err = capsys.readouterr()
    records = json.loads(out)
    assert {(r["model"], r["verdict"]) for r in records} == {("a", "wrong"), ("b", "optimal")}
    assert all(r["agrees"] is True for r in records)  # the presets agree with each other: only .solu tells
    assert "2 answers are wrong" in err

    write_solu(solu, {"a": Known("opt", opt_a), "b": Known("best", opt_b)}, [])
    assert main(["bench", str(folder), "--solu", str(solu), *BENCH, "--json"]) == 0
    assert {r["verdict"] for r in json.loads(capsys.readouterr().out)} == {"optimal"}


def test_a_folders_own_solu_file_is_used_and_said(instance_folder, tmp_path, capsys):
    folder, (opt_a, _) = instance_folder
    own = tmp_path / "set"
    own.mkdir()
    for name in ("a.npz", "b.npz"):
        (own / name).write_bytes((folder / name).read_bytes())
    write_solu(own / "rpbench.solu", {"a": Known("opt", opt_a - 1)}, ["test"])
    assert main(["bench", str(own), *BENCH, "--json"]) == 1
    out, err = capsys.readouterr()
    assert f"known values from {own / 'rpbench.solu'}" in err
    assert [r["verdict"] for r in json.loads(out) if r["model"] == "a"] == ["wrong", "wrong"]


@pytest.mark.parametrize(
    "text, match",
    [
        ("=opt= nosuch 5\n", "'nosuch' names no instance benchmarked here"),
        ("=opt= a 5\n=opt= a 6\n", "line 2: instance 'a' is given again"),
    ],
)
def test_a_bad_solu_file_is_one_line_before_any_solve(instance_folder, tmp_path, capsys, monkeypatch, text, match):
    folder, _ = instance_folder
    (tmp_path / "x.solu").write_text(text)
    monkeypatch.setattr("rpbench.commands.bench.run_benchmark", lambda *a, **k: pytest.fail("benchmarked"))
    assert main(["bench", str(folder), "--solu", str(tmp_path / "x.solu"), *BENCH]) == 2
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1


def test_a_time_limited_run_is_unsolved_and_counted_at_the_limit():
    model = synthetic.pairing(300, seed=1, objective="cardinality_then_weight")  # HiGHS: about 1 s
    table = run_benchmark([model], BenchSpec(["highs", "matching"], time_limit_s=0.02))
    highs = table[table["preset"] == "highs"].iloc[0]
    assert highs["status"] == "time_limit" and highs["verdict"] == "time_limit" and highs["time_limit_s"] == 0.02
    summary = summarise(table, shift=0.0).set_index("preset")
    assert summary.loc["highs", "solved"] == 0 and summary.loc["highs", "time_limit"] == 1
    assert summary.loc["highs", "sgm_s"] == pytest.approx(0.02)  # the limit, not the time it took
    assert summary.loc["matching", "solved"] == 1


def test_a_solve_over_the_memory_limit_reports_memory_limit():
    model = synthetic.pairing(300, seed=1)
    # 0.1 GB is less than the worker holds once HiGHS is imported: its next allocation fails
    table = run_benchmark([model], BenchSpec(["highs"], isolate=True, memory_limit_gb=0.1))
    row = table.iloc[0]
    assert row["status"] == "memory_limit" and row["verdict"] == "memory_limit"
    assert "memory limit of 0.1 GB" in row["message"] and math.isnan(row["total_s"])


def test_a_worker_that_dies_under_a_memory_limit_reports_memory_limit_else_killed():
    from bench.crash_backend import Crash

    preset = Preset.of(Crash())
    models = [synthetic.pairing(20, seed=1).renamed("crash"), synthetic.pairing(20, seed=2)]
    limited = run_benchmark(models, BenchSpec([preset], isolate=True, memory_limit_gb=8))
    assert limited["verdict"].tolist() == ["memory_limit", "optimal"]  # a new worker takes the next model
    assert "signal SIGKILL" in limited["message"][0] and "memory limit of 8 GB" in limited["message"][0]
    unlimited = run_benchmark(models[:1], BenchSpec([preset], isolate=True))
    assert unlimited["verdict"].tolist() == ["killed"] and "signal SIGKILL" in unlimited["message"][0]


def test_memory_limit_needs_an_isolated_worker(capsys):
    assert main(["bench", "--synthetic", "--sizes", "tiny", "--no-isolate", "--memory-limit", "4"]) == 2
    assert "--memory-limit caps an isolated worker" in capsys.readouterr().err
    assert main(["bench", "--synthetic", "--sizes", "tiny", "--memory-limit", "0"]) == 2
    assert "--memory-limit 0 is out of range" in capsys.readouterr().err
