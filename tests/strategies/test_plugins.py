"""Strategies defined outside rpbench: ``module:Class`` and entry points, their run names, errors and options.

A plug-in module is written to a temporary folder put on ``sys.path``; entry
points are declared by a hand-written ``.dist-info`` folder there (what pip
writes), or, in the slow test, by pip-installing the example package of
``examples/rpbench-greedy`` into a temporary target folder (the environment
itself is never changed).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from helpers import line_network, round_state
from plugin_helpers import EXAMPLE, declare_entry_points, forget

from rpbench import plugins
from rpbench.check import check_folder
from rpbench.cli import main
from rpbench.commands._runs import parse_runs
from rpbench.exceptions import ModelError, ParameterError
from rpbench.model import Structure
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.results.metrics import TIMING_KPIS
from rpbench.spec import resolve_runs
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class, strategy_plugin_names
from rpbench.strategies.base import Kind, received
from rpbench.strategies.myopic import MyopicBatch
from rpbench.strategies.rtv import RTV

MODULE = '''
from dataclasses import dataclass

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.strategies.base import Strategy
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M, assignment_round, join_options, vacant_options
from rpbench.options import RunOptions, option


@dataclass(frozen=True)
class MyOptions(RunOptions):
    x: int = option(0, "an integer that changes nothing")

    def __post_init__(self):
        if self.x < 0:
            raise ParameterError("mymod: x must be >= 0")


class MyStrategy(Strategy):
    """MB under another name."""

    name = "mine"
    label = "Mine"
    color = "tab:pink"
    structure = Structure.ASSIGNMENT
    Options = MyOptions

    def build(self, state):
        vac, join = vacant_options(state), join_options(state)
        return assignment_round(state, vac, -vac.pickup_m, join, join.saving_m - join.pickup_m,
                                np.full(state.n_passengers, NO_WAIT_UTILITY_M), name="mine")


class Twin(MyStrategy):
    """Another class under the same run name."""


class Builtin(MyStrategy):
    name = "mb"


class Abstract(Strategy):
    name = "abstract"
    label = "Abstract"
    structure = Structure.ASSIGNMENT


def helper():
    return None
'''


@pytest.fixture
def plugin_dir(tmp_path, monkeypatch):
    """A folder on sys.path holding ``mymod`` (fresh for each test: no module or entry point cached across)."""
    folder = tmp_path / "plugins"
    folder.mkdir()
    (folder / "mymod.py").write_text(MODULE)
    forget("mymod")
    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.syspath_prepend(str(folder))
    yield folder
    forget("mymod")


# ------------------------------------------------------------------ module:Class
def test_module_class_strategy_runs_everywhere_a_builtin_does(plugin_dir, tmp_path, capsys):
    out = tmp_path / "run"
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--sample",
            "0.1",
            "--strategies",
            "mb,mymod:MyStrategy",
            "--opt",
            "mymod:MyStrategy.x=3",
            "--out",
            str(out),
            "--no-progress",
            "--json",
        ]
    )
    assert code == 0, capsys.readouterr().err
    kpis = json.loads(capsys.readouterr().out)["kpis"]
    assert list(kpis) == ["mb", "mine"]  # the plug-in runs under its class's name
    same = {k: v for k, v in kpis["mb"].items() if k not in TIMING_KPIS}
    assert {k: kpis["mine"][k] for k in same} == pytest.approx(same, nan_ok=True)  # MB, renamed
    assert (out / "runs" / "mine" / "events.csv.gz").is_file()
    meta = json.loads((out / "meta.json").read_text())
    assert meta["strategies"] == ["mb", "mine"]
    record = meta["runs"]["mine"]
    assert record["options"] == {"x": 3} and record["source"] == "mymod:MyStrategy"
    assert (record["label"], record["color"]) == ("Mine", "tab:pink")  # what a report needs, without the class
    checks = check_folder(out)
    assert [c.run for c in checks] == ["mb", "mine"] and all(c.ok for c in checks)
    assert main(["check", str(out)]) == 0
    assert "| Metric | MB | Mine |" in (out / "report.md").read_text()
    # the folder re-renders from its files alone: the plug-in need not be importable any more
    forget("mymod")
    sys.path.remove(str(plugin_dir))
    (out / "report.md").unlink()
    assert main(["report", str(out)]) == 0
    assert "| Metric | MB | Mine |" in (out / "report.md").read_text()


def names(items: str) -> list[tuple[str, str]]:
    return [(e.name, e.source) for e in resolve_runs(items.split(","))]


def test_sources_keep_their_case_and_builtin_names_do_not(plugin_dir):
    """A ``module:Class`` source is case-sensitive (Python names are); built-in names are not."""
    assert names(" MB, mymod:MyStrategy ,Oracle1") == [
        ("mb", "mb"),
        ("mine", "mymod:MyStrategy"),
        ("oracle1", "oracle1"),
    ]
    with pytest.raises(ParameterError, match="names 'mine' twice"):
        names("mymod:MyStrategy,mymod:MyStrategy")
    with pytest.raises(ParameterError, match="has no attribute 'mystrategy'"):
        names("mymod:mystrategy")


def test_two_plugins_under_one_run_name_or_a_builtin_name_are_refused(plugin_dir):
    """The run name is the class's ``name``: two classes sharing one, or one taking a built-in's, fail."""
    with pytest.raises(ParameterError, match="runs 'mymod:MyStrategy' and 'mymod:Twin' as 'mine'"):
        names("mymod:MyStrategy,mymod:Twin")
    with pytest.raises(ParameterError, match="declares name 'mb', the name of a built-in run"):
        names("mymod:Builtin")


@pytest.mark.parametrize(
    "spec, message",
    [
        (
            "nomod_xyz:Thing",
            "strategy 'nomod_xyz:Thing': cannot import module 'nomod_xyz' (No module named "
            "'nomod_xyz'); install it or put its folder on PYTHONPATH",
        ),
        ("mymod.sub:Thing", "cannot import module 'mymod.sub' (No module named 'mymod.sub'; 'mymod' is not a package)"),
        ("mymod:Missing", "strategy 'mymod:Missing': module 'mymod' has no attribute 'Missing'"),
        (
            "mymod:helper",
            "strategy 'mymod:helper': mymod.helper is a function, not a subclass of rpbench.strategies.base.Strategy",
        ),
        ("mymod:MyOptions", "mymod.MyOptions is a class, not a subclass of rpbench.strategies.base.Strategy"),
        ("mymod:Abstract", "mymod.Abstract is abstract; implement build"),
        ("my-mod:Thing", "strategy 'my-mod:Thing' is not MODULE:CLASS"),
        ("mymod:", "strategy 'mymod:' is not MODULE:CLASS"),
        (
            "nosuch",
            f"unknown strategy 'nosuch'; choose from {', '.join([*STRATEGY_REGISTRY, *ORACLE_RUNS])}, "
            "or give a strategy class as MODULE:CLASS",
        ),
    ],
)
def test_bad_plugins_are_one_line_and_exit_2(plugin_dir, tmp_path, capsys, spec, message):
    out = tmp_path / "never"
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--sample",
            "0.1",
            "--strategies",
            f"mb,{spec}",
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_a_class_lacking_a_declared_attribute_is_refused(plugin_dir):
    (plugin_dir / "nolabel.py").write_text(
        textwrap.dedent("""
        from rpbench.model import Structure
        from rpbench.strategies.base import Strategy

        class NoLabel(Strategy):
            name = "nolabel"
            structure = Structure.ASSIGNMENT

            def build(self, state):
                raise NotImplementedError
    """)
    )
    forget("nolabel")
    with pytest.raises(ParameterError, match="nolabel.NoLabel lacks the class attribute.s. label every strategy"):
        strategy_class("nolabel:NoLabel")
    forget("nolabel")


# ------------------------------------------------------------------ --opt
def options(strategies: str, *items: str) -> dict:
    return {e.name: e.options for e in parse_runs(strategies, items)}


def test_opt_reaches_the_typed_options_of_a_plugin_by_name_or_source(plugin_dir):
    """``--opt NAME.x=...`` uses the run's name; the source it was given by works too."""
    got = options("mb,mymod:MyStrategy", "mine.x=7", "mb.order_rule=min_then_check")
    assert got["mine"].x == 7 and got["mine"].as_dict() == {"x": 7} and type(got["mine"]).__name__ == "MyOptions"
    assert got["mb"].order_rule == "min_then_check"
    assert options("mymod:MyStrategy", "mymod:MyStrategy.x=5")["mine"].x == 5
    with pytest.raises(ParameterError, match="mine: unknown option 'y'; known options: x"):
        options("mymod:MyStrategy", "mine.y=1")
    with pytest.raises(ParameterError, match="option x = 'many' must be an integer"):
        options("mymod:MyStrategy", "mine.x=many")
    with pytest.raises(ParameterError, match="mymod: x must be >= 0"):
        options("mymod:MyStrategy", "mine.x=-1")
    with pytest.raises(ParameterError, match="run 'mymod:Other' is not in --strategies"):
        options("mymod:MyStrategy", "mymod:Other.x=1")
    with pytest.raises(ParameterError, match="expected RUN.KEY=VALUE"):
        options("mymod:MyStrategy", "mine=1")


def test_cli_opt_of_a_spec_unknown_option_exits_2(plugin_dir, tmp_path, capsys):
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--strategies",
            "mymod:MyStrategy",
            "--opt",
            "mine.z=1",
            "--out",
            str(tmp_path / "never"),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "unknown option 'z'" in err[0]


# ------------------------------------------------------------------ entry points
def test_entry_points_resolve_and_builtins_win(plugin_dir):
    declare_entry_points(
        plugin_dir,
        "mine_dist",
        "rpbench.strategies",
        {
            "MyPlug": "mymod:MyStrategy",
            "mb": "mymod:MyStrategy",
            "oracle1": "mymod:MyStrategy",
            "broken": "nomod_xyz:Thing",
            "notone": "mymod:helper",
        },
    )
    assert strategy_class("myplug").__name__ == "MyStrategy"
    assert strategy_class("MYPLUG") is strategy_class("myplug")  # names compare case-insensitively
    assert strategy_class("mb") is MyopicBatch  # a shadowing entry point is ignored
    assert "myplug" in strategy_plugin_names() and "mb" not in strategy_plugin_names()
    # oracles win too; the plug-in runs under its class's name
    assert names("mb,MyPlug,oracle1") == [("mb", "mb"), ("mine", "myplug"), ("oracle1", "oracle1")]
    with pytest.raises(
        ParameterError,
        match=r"strategy 'broken' \(entry point broken = nomod_xyz:Thing of "
        r"mine_dist\): cannot import module 'nomod_xyz'",
    ):
        names("broken")
    with pytest.raises(ParameterError, match="mymod.helper is a function, not a subclass"):
        strategy_class("notone")
    with pytest.raises(ParameterError, match="installed plug-ins: broken, myplug, notone"):
        strategy_class("nosuch")
    assert options("myplug", "mine.x=2")["mine"].x == 2


def test_rpbench_list_names_a_broken_plugin_and_lists_the_rest(plugin_dir, capsys):
    declare_entry_points(plugin_dir, "mine_dist", "rpbench.strategies", {"broken": "nomod_xyz:Thing"})
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "broken           BROKEN: strategy 'broken' (entry point broken = nomod_xyz:Thing" in out
    assert "\n  mb " in out and "\n  bound " in out  # the others are still listed


def test_one_name_declared_by_two_distributions_is_ambiguous(plugin_dir):
    declare_entry_points(plugin_dir, "first_dist", "rpbench.strategies", {"twice": "mymod:MyStrategy"})
    declare_entry_points(plugin_dir, "second_dist", "rpbench.strategies", {"twice": "mymod:Abstract"})
    with pytest.raises(ParameterError, match="strategy 'twice' is ambiguous.*mymod:Abstract and mymod:MyStrategy"):
        strategy_class("twice")


# ------------------------------------------------------------------ sweeps, snapshots
@pytest.mark.slow
def test_sweep_and_snapshot_with_a_plugin_strategy(plugin_dir, tmp_path, capsys):
    out = tmp_path / "sweep"
    code = main(
        [
            "sweep",
            "--over",
            "dt=10,30",
            "--scenario",
            "toy",
            "--sample",
            "0.1",
            "--strategies",
            "mb,mymod:MyStrategy",
            "--opt",
            "mine.x=2",
            "--workers",
            "1",
            "--out",
            str(out),
        ]
    )
    assert code == 0, capsys.readouterr().err
    for point in ("dt=10", "dt=30"):
        assert all(c.ok for c in check_folder(out / point))
        meta = json.loads((out / point / "meta.json").read_text())
        assert meta["runs"]["mine"]["options"] == {"x": 2}
    assert "Response rate Mine" in (out / "report.md").read_text()
    assert main(["report", str(out)]) == 0
    snap = tmp_path / "snap"
    assert (
        main(
            [
                "snapshot",
                "--scenario",
                "toy",
                "--sample",
                "0.1",
                "--strategies",
                "mymod:MyStrategy",
                "--largest",
                "1",
                "--out",
                str(snap),
                "--json",
            ]
        )
        == 0
    )
    manifest = json.loads((snap / "manifest.json").read_text())
    assert [e["strategy"] for e in manifest["instances"]] == ["mine"]
    assert (snap / manifest["instances"][0]["file"]).is_file()


# ------------------------------------------------------------------ the example package, installed by pip
def pip_install(source: Path, target: Path) -> None:
    """``pip install`` the example into ``target`` (never into the environment).

    Without build isolation, as the environment's own setuptools builds it,
    when that can build wheels; otherwise pip fetches the build requirements
    into an isolated build environment.
    """
    try:
        import wheel  # noqa: F401

        can_build = True
    except ImportError:
        can_build = int(metadata.version("setuptools").split(".")[0]) >= 71
    isolation = ["--no-build-isolation"] if can_build else []
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "--no-input",
            "--quiet",
            *isolation,
            "--target",
            str(target),
            str(source),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.slow
def test_example_package_runs_by_entry_point_and_preset(tmp_path, monkeypatch):
    source = tmp_path / "src"  # a copy: building writes build/ and *.egg-info into the source
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    target = tmp_path / "site"
    pip_install(source, target)
    assert (target / "rpbench_greedy" / "dense-lsa.toml").is_file()
    forget("rpbench_greedy")
    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.syspath_prepend(str(target))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(target), os.environ.get("PYTHONPATH", "")]))
    try:
        from rpbench.backends.registry import backend_plugin_names as backend_plugins

        assert "greedy" in strategy_plugin_names() and "dense-lsa" in backend_plugins()
        preset = str(target / "rpbench_greedy" / "dense-lsa.toml")
        out = tmp_path / "run"
        assert (
            main(
                [
                    "run",
                    "--scenario",
                    "toy",
                    "--sample",
                    "0.2",
                    "--strategies",
                    "mb,greedy,bound",
                    "--opt",
                    "greedy.pickup_weight=3",
                    "--solver",
                    preset,
                    "--oracle-solver",
                    "matching",
                    "--out",
                    str(out),
                    "--no-progress",
                ]
            )
            == 0
        )
        meta = json.loads((out / "meta.json").read_text())
        assert meta["preset"]["backend"] == "dense-lsa" and meta["runs"]["greedy"]["options"]["pickup_weight"] == 3
        assert all(c.ok for c in check_folder(out))
        assert "| Metric | MB | Greedy | Upper bound" in (out / "report.md").read_text()
        # a fresh process finds both plug-ins from PYTHONPATH alone
        fresh = subprocess.run(
            [
                sys.executable,
                "-m",
                "rpbench.cli",
                "run",
                "--scenario",
                "toy",
                "--sample",
                "0.1",
                "--strategies",
                "greedy",
                "--solver",
                preset,
                "--out",
                str(tmp_path / "fresh"),
                "--no-progress",
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert fresh.returncode == 0, fresh.stderr[-3000:]
        assert json.loads(fresh.stdout)["kpis"]["greedy"]["orders"] == 40
        assert all(c.ok for c in check_folder(tmp_path / "fresh"))
    finally:
        forget("rpbench_greedy")


# ------------------------------------------------------------------ what the simulator receives from build()
def rtv_round():
    """An RTV round (trip packing): three passengers, two vacant vehicles, one partly occupied."""
    net = line_network(6)
    state = round_state(
        net, [(0, 4), (1, 5), (2, 5)], [(0, 0.0), (1, 0.0)], occupied=[{"node": 3, "origin": 3, "destination": 5}]
    )
    return state, RTV().build(state)


def test_a_received_round_model_is_a_read_only_copy():
    state, rm = rtv_round()
    got = received(rm, state, Structure.TRIP_PACKING)
    assert got.model.values is not rm.model.values and np.array_equal(got.model.values, rm.model.values)
    arrays = [got.model.values, got.model.col_vehicle, got.kind, got.vehicle, got.first, got.second, got.fofo]
    assert not any(a.flags.writeable for a in arrays)
    rm.model.values[0] = np.nan  # the strategy's own arrays stay its own
    assert np.isfinite(got.model.values).all()


def test_a_trip_may_list_its_passengers_in_either_pick_up_order():
    state, rm = rtv_round()
    trip = int(np.flatnonzero(rm.kind == Kind.TRIP2)[0])
    rm.first[trip], rm.second[trip] = rm.second[trip], rm.first[trip]
    received(rm, state, Structure.TRIP_PACKING)


@pytest.mark.parametrize(
    "spoil, message",
    [
        (lambda rm, trip: rm.second.__setitem__(trip, 99), "but its model column serves orders"),
        (lambda rm, trip: rm.kind.__setitem__(trip, Kind.VACANT), "but its model column is a two-passenger trip"),
        (lambda rm, trip: rm.kind.__setitem__(-1, Kind.VACANT), "is a partly occupied vehicle's (a V1 row)"),
        (lambda rm, trip: rm.vehicle.__setitem__(trip, 2), "stands for vehicle"),
        (lambda rm, trip: rm.kind.__setitem__(0, 9), "column 0 has kind 9, but"),
        (lambda rm, trip: rm.pickup_m.__setitem__(trip, np.inf), "needs finite ones"),
        (lambda rm, trip: rm.model.col_request1.__setitem__(0, 7), "column 0 has first request 7"),
    ],
)
def test_a_spoilt_trip_packing_round_is_refused(spoil, message):
    state, rm = rtv_round()
    trip = int(np.flatnonzero(rm.kind == Kind.TRIP2)[0])
    spoil(rm, trip)
    with pytest.raises(ModelError, match=re.escape(message)):
        received(rm, state, Structure.TRIP_PACKING)


def test_a_round_model_of_another_structure_is_refused():
    state, rm = rtv_round()
    with pytest.raises(ModelError, match="a strategy of structure assignment returns an AssignmentModel"):
        received(rm, state, Structure.ASSIGNMENT)
    with pytest.raises(ModelError, match="build.. returned a tuple, not a RoundModel"):
        received((rm,), state, Structure.TRIP_PACKING)
