"""Strategies defined outside rpbench: ``module:Class`` run names, entry points, their errors and options.

A plug-in module is written to a temporary folder put on ``sys.path``; entry
points are declared by a hand-written ``.dist-info`` folder there (what pip
writes), or, in the slow test, by pip-installing the example package of
``examples/rpbench-greedy`` into a temporary target folder (the environment
itself is never changed).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from importlib import metadata
from pathlib import Path

import pytest
from plugin_helpers import EXAMPLE, declare_entry_points, forget

from rpbench import plugins
from rpbench.cli import main
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import parse_run_options, parse_strategies, split_option_key
from rpbench.results.check import check_folder
from rpbench.results.runs import run_color, run_label
from rpbench.strategies import plugin_names, strategy_class
from rpbench.strategies.myopic import MyopicBatch

MODULE = '''
from dataclasses import dataclass

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.strategies.base import Strategy
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M, assignment_round, join_options, vacant_options
from rpbench.strategies.options import RunOptions, option


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
    assert list(kpis) == ["mb", "mymod:MyStrategy"]
    same = {k: v for k, v in kpis["mb"].items() if k != "wall_s"}
    assert {k: kpis["mymod:MyStrategy"][k] for k in same} == pytest.approx(same, nan_ok=True)  # MB, renamed
    assert (out / "runs" / "mymod:MyStrategy" / "events.csv.gz").is_file()
    meta = json.loads((out / "meta.json").read_text())
    assert meta["strategies"] == ["mb", "mymod:MyStrategy"]
    assert meta["runs"]["mymod:MyStrategy"]["options"] == {"x": 3}
    checks = check_folder(out)
    assert [c.run for c in checks] == ["mb", "mymod:MyStrategy"] and all(c.ok for c in checks)
    assert main(["check", str(out)]) == 0
    assert "| Metric | MB | Mine |" in (out / "report.md").read_text()
    assert (run_label("mymod:MyStrategy"), run_color("mymod:MyStrategy")) == ("Mine", "tab:pink")


def test_spec_names_keep_their_case_and_builtin_names_do_not(plugin_dir):
    assert parse_strategies(" MB, mymod:MyStrategy ,Oracle1") == ["mb", "mymod:MyStrategy", "oracle1"]
    with pytest.raises(ParameterError, match="names a strategy twice"):
        parse_strategies("mymod:MyStrategy,mymod:MyStrategy")
    with pytest.raises(ParameterError, match="has no attribute 'mystrategy'"):
        parse_strategies("mymod:mystrategy")


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
            "unknown strategy 'nosuch'; choose from np, mb, rtv, fl-nd, fl, bound, oracle1, oracle2, "
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
    assert run_label("nolabel:NoLabel") == "nolabel:NoLabel"  # a report falls back to the run name
    forget("nolabel")


# ------------------------------------------------------------------ --opt
def test_opt_reaches_the_typed_options_of_a_spec(plugin_dir):
    options = parse_run_options(["mymod:MyStrategy.x=7", "mb.order_rule=min_then_check"], ["mb", "mymod:MyStrategy"])
    assert options["mymod:MyStrategy"].x == 7 and options["mymod:MyStrategy"].as_dict() == {"x": 7}
    assert type(options["mymod:MyStrategy"]).__name__ == "MyOptions"
    assert options["mb"].order_rule == "min_then_check"
    with pytest.raises(ParameterError, match="mymod:MyStrategy: unknown option 'y'; known options: x"):
        parse_run_options(["mymod:MyStrategy.y=1"], ["mymod:MyStrategy"])
    with pytest.raises(ParameterError, match="option x = 'many' must be an integer"):
        parse_run_options(["mymod:MyStrategy.x=many"], ["mymod:MyStrategy"])
    with pytest.raises(ParameterError, match="mymod: x must be >= 0"):
        parse_run_options(["mymod:MyStrategy.x=-1"], ["mymod:MyStrategy"])
    with pytest.raises(ParameterError, match="strategy 'mymod:Other' is not in --strategies"):
        parse_run_options(["mymod:Other.x=1"], ["mymod:MyStrategy"])
    with pytest.raises(ParameterError, match="expected STRATEGY.KEY=VALUE"):
        parse_run_options(["mymod:MyStrategy=1"], ["mymod:MyStrategy"])


def test_opt_key_splits_at_the_longest_run_name():
    assert split_option_key("pkg.rules:Greedy.threshold", ["mb", "pkg.rules:Greedy"]) == (
        "pkg.rules:Greedy",
        "threshold",
    )
    assert split_option_key("a.b.c", ["a", "a.b"]) == ("a.b", "c")
    assert split_option_key("rtv.c_ko", ["rtv"]) == ("rtv", "c_ko")
    # not a run of the list: a guess for the error message (a dotted module before the colon stays whole)
    assert split_option_key("pkg.rules:Other.x", ["mb"]) == ("pkg.rules:Other", "x")
    assert split_option_key("fl.rates", ["mb"]) == ("fl", "rates")
    assert split_option_key("rtv", ["rtv"]) == ("rtv", "")


def test_cli_opt_of_a_spec_unknown_option_exits_2(plugin_dir, tmp_path, capsys):
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--strategies",
            "mymod:MyStrategy",
            "--opt",
            "mymod:MyStrategy.z=1",
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
    assert "myplug" in plugin_names() and "mb" not in plugin_names()
    assert parse_strategies("mb,MyPlug,oracle1") == ["mb", "myplug", "oracle1"]  # oracles win too
    with pytest.raises(
        ParameterError,
        match=r"strategy 'broken' \(entry point broken = nomod_xyz:Thing of "
        r"mine_dist\): cannot import module 'nomod_xyz'",
    ):
        parse_strategies("broken")
    with pytest.raises(ParameterError, match="mymod.helper is a function, not a subclass"):
        strategy_class("notone")
    with pytest.raises(ParameterError, match="installed plug-ins: broken, myplug, notone"):
        strategy_class("nosuch")
    options = parse_run_options(["myplug.x=2"], ["myplug"])
    assert options["myplug"].x == 2


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
            "mymod:MyStrategy.x=2",
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
        assert meta["runs"]["mymod:MyStrategy"]["options"] == {"x": 2}
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
    assert [e["strategy"] for e in manifest["instances"]] == ["mymod:MyStrategy"]
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
        from rpbench.backends.registry import plugin_names as backend_plugins

        assert "greedy" in plugin_names() and "dense-lsa" in backend_plugins()
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
