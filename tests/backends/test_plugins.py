"""Backends defined outside rpbench: ``module:Class`` and entry-point names, in presets and in runs.

The backend under test is the example plug-in of ``examples/rpbench-greedy``
(its folder put on ``sys.path``); the slow test of
``tests/strategies/test_plugins.py`` installs the same package with pip.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from plugin_helpers import EXAMPLE, declare_entry_points, forget

from rpbench import plugins
from rpbench.backends import backend_class, load_preset, solve
from rpbench.backends.highs import HighsBackend
from rpbench.backends.presets import parse_preset
from rpbench.backends.registry import backend_plugin_names
from rpbench.bench import synthetic
from rpbench.check import check_folder
from rpbench.cli import main
from rpbench.exceptions import PresetError, SolverError
from rpbench.harness.comparison import run_comparison
from rpbench.model import Status
from rpbench.results.metrics import TIMING_KPIS
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

SPEC = "rpbench_greedy.backend:DenseLSABackend"


@pytest.fixture
def example(tmp_path, monkeypatch):
    """The example package importable from its source folder, and a folder for presets and dist-infos."""
    forget("rpbench_greedy")
    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.syspath_prepend(str(EXAMPLE))
    folder = tmp_path / "site"
    folder.mkdir()
    monkeypatch.syspath_prepend(str(folder))
    yield folder
    forget("rpbench_greedy")


def preset_file(folder, backend: str, options: str = "") -> str:
    path = folder / "mine.toml"
    path.write_text(f'backend = "{backend}"\ndescription = "a plug-in backend"\n[options]\n{options}')
    return str(path)


def test_a_module_class_backend_solves_a_toy_run_through_a_preset_file(example, tmp_path):
    preset = load_preset(preset_file(example, SPEC))
    assert preset.backend == SPEC and type(preset.adapter()).__name__ == "DenseLSABackend"
    request = ScenarioRequest("toy", sample=0.1, seed=2)
    outcome = run_comparison(RunSpec.of(request, ["mb", "fl"], preset=preset.path), tmp_path / "run", progress=False)
    folder, table = outcome.folder, outcome.table
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["preset"]["backend"] == SPEC and meta["preset"]["name"] == "mine"
    assert all(c.ok for c in check_folder(folder))
    # the same optimum as a built-in exact backend (the simulator breaks ties canonically)
    reference = run_comparison(RunSpec.of(request, ["mb", "fl"]), tmp_path / "highs", progress=False).table
    same = [k for k in table.index if k not in TIMING_KPIS]
    assert np.allclose(table.loc[same].to_numpy(float), reference.loc[same].to_numpy(float), equal_nan=True)


def test_a_plugin_backend_is_refused_for_structures_it_does_not_solve(example, tmp_path):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=2), ["rtv"], preset=preset_file(example, SPEC))
    with pytest.raises(PresetError, match="does not solve trip_packing models exactly"):
        run_comparison(spec, tmp_path / "never", progress=False)
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("seed", range(6))
def test_the_example_backend_agrees_with_highs(example, seed):
    lsa = load_preset(preset_file(example, SPEC))
    model = synthetic.assignment(30 + 7 * seed, 12 + 5 * seed, seed=seed, wait=seed % 2 == 0)
    got, want = solve(model, lsa), solve(model, load_preset("highs"))
    assert got.status == want.status
    if want.status is Status.OPTIMAL:
        assert got.objective == want.objective and got.gap == 0.0 and got.backend == "dense-lsa"


def test_the_example_backend_is_honest_about_what_it_cannot_do(example, monkeypatch):
    model = synthetic.assignment(20, 8, seed=1)
    with pytest.raises(PresetError, match="cannot honour option.s. time_limit_s, method"):
        solve(model, load_preset(preset_file(example, SPEC, 'time_limit_s = 10.0\nmethod = "fast"\n')))
    monkeypatch.setattr(sys.modules["rpbench_greedy.backend"], "MAX_CELLS", 100)
    with pytest.raises(SolverError, match="needs a 20 x 28 dense matrix"):
        solve(model, load_preset(preset_file(example, SPEC)))
    infeasible = synthetic.assignment(10, 2, seed=1, wait=False)  # 10 passengers, 2 vehicles, no waiting
    monkeypatch.setattr(sys.modules["rpbench_greedy.backend"], "MAX_CELLS", 10**6)
    assert solve(infeasible, load_preset(preset_file(example, SPEC))).status is Status.INFEASIBLE


@pytest.mark.parametrize(
    "backend, message",
    [
        (
            "nomod_xyz:Thing",
            "solver preset '.*mine.toml': backend 'nomod_xyz:Thing': cannot import module 'nomod_xyz' "
            r"\(No module named 'nomod_xyz'\)",
        ),
        ("rpbench_greedy.backend:Nope", "module 'rpbench_greedy.backend' has no attribute 'Nope'"),
        (
            "rpbench_greedy.backend:SolveOptions",
            "rpbench_greedy.backend.SolveOptions is a class, not a subclass of rpbench.backends.base.Backend",
        ),
        ("rpbench_greedy.backend:Backend", "rpbench_greedy.backend.Backend is abstract; implement solve"),
        ("rpbench_greedy:PRESET", "rpbench_greedy.PRESET is a PosixPath, not a subclass"),
        ("cplex", "backend = 'cplex' is not one of highs, .* nor a \"module:Class\" spec"),
        ("a b:C", "backend 'a b:C' is not MODULE:CLASS"),
    ],
)
def test_bad_plugin_backends_in_presets(example, backend, message):
    with pytest.raises(PresetError, match=message):
        load_preset(preset_file(example, backend))


def test_cli_reports_a_bad_plugin_preset_on_one_line(example, tmp_path, capsys):
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--strategies",
            "mb",
            "--solver",
            preset_file(example, "nomod_xyz:T"),
            "--out",
            str(tmp_path / "never"),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()  # the scenario's label comes first, as a note
    errors = [line for line in err if line.startswith("rpbench: error:")]
    assert code == 2 and errors == err[-1:] and "cannot import module 'nomod_xyz'" in err[-1]


def test_backend_entry_points_resolve_and_builtins_win(example):
    declare_entry_points(example, "lsa_dist", "rpbench.backends", {"LSA": SPEC, "highs": SPEC})
    assert backend_class("lsa").__name__ == "DenseLSABackend" and backend_class("highs") is HighsBackend
    assert "lsa" in backend_plugin_names() and "highs" not in backend_plugin_names()
    preset = parse_preset("mine", 'backend = "lsa"\n', "mine.toml")
    assert preset.backend == "lsa" and type(preset.adapter()) is backend_class(SPEC)
    with pytest.raises(
        PresetError,
        match="unknown backend 'gurobi'; known backends: highs, .*; installed plug-ins: lsa; or give MODULE:CLASS",
    ):
        backend_class("gurobi")
    with pytest.raises(PresetError, match="is not one of highs, ortools, pyomo, cvxpy, scipy, matching, blossom, lsa"):
        parse_preset("bad", 'backend = "gurobi"\n', "bad.toml")
