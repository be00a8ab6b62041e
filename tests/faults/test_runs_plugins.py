"""Plug-ins that answer wrongly: one error line naming the plug-in and the fault, exit status 2, nothing written.

The plug-in module (strategies and backends written as a researcher would, each with one mistake)
is written to a temporary folder put on ``sys.path`` and named as ``module:Class``. A strategy's
round model is checked where the simulator receives it, after ``build()`` returned (a strategy may
change its arrays after constructing them); a backend's answer before it is used. A long HiGHS
solve ends at SIGTERM with the CLI's interruption handling.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from plugin_helpers import forget

from faults.test_runs_helpers import TOY, assert_nothing_written, assert_one_error, run_cli
from rpbench import plugins
from rpbench.backends.highs import HighsBackend

MODULE = '''
import dataclasses
import os
import signal
import threading

import numpy as np

from rpbench.backends.base import SolveOptions
from rpbench.backends.highs import HighsBackend
from rpbench.bench import synthetic
from rpbench.model import Status
from rpbench.strategies.candidates import assignment_round, join_options, vacant_options
from rpbench.strategies.myopic import MyopicBatch


class NoModel(MyopicBatch):
    name = "nomodel"

    def build(self, state):
        super().build(state)  # forgets to return it


class NanCost(MyopicBatch):
    name = "nancost"

    def build(self, state):
        vac, join = vacant_options(state), join_options(state)
        return assignment_round(state, vac, np.full(len(vac.p), np.nan), join, -join.pickup_m,
                                np.zeros(state.n_passengers), name="nancost")


class NanLater(MyopicBatch):
    name = "nanlater"

    def build(self, state):
        rm = super().build(state)
        rm.model.values[:] = np.nan  # after the model validated itself
        return rm


class OutOfRange(MyopicBatch):
    name = "outofrange"

    def build(self, state):
        rm = super().build(state)
        rm.model.col_passenger[0] = rm.model.n_passengers + 4
        return rm


class KindsSwapped(MyopicBatch):
    name = "kinds"

    def build(self, state):
        rm = super().build(state)
        rm.kind[:] = np.where(rm.kind == 0, 1, 0)  # wait <-> vacant
        return rm


class WrongOrder(MyopicBatch):
    name = "wrongorder"

    def build(self, state):
        rm = super().build(state)
        rm.first[:] = rm.first + 1000
        return rm


class ShortDecoding(MyopicBatch):
    name = "short"

    def build(self, state):
        rm = super().build(state)
        return dataclasses.replace(rm, fofo=rm.fofo[:-1])


class BadMove(MyopicBatch):
    name = "badmove"

    def reposition(self, state, rm, chosen):
        return np.array([0]), np.array([10**9])


class ReturnsNone(HighsBackend):
    name = "returns-none"

    def solve(self, model, options, **kw):
        super().solve(model, options, **kw)


class WrongLength(HighsBackend):
    """Returns the 0/1 vector x (and one entry too many) where column indices belong."""

    name = "wrong-length"

    def solve(self, model, options, **kw):
        s = super().solve(model, options, **kw)
        x = np.zeros(model.n_cols + 1, np.int64)
        x[s.chosen] = 1
        return dataclasses.replace(s, chosen=x)


class Fractional(HighsBackend):
    name = "fractional"

    def solve(self, model, options, **kw):
        s = super().solve(model, options, **kw)
        return dataclasses.replace(s, chosen=s.chosen + 0.5)


class Infeasible(HighsBackend):
    name = "infeasible"

    def solve(self, model, options, **kw):
        s = super().solve(model, options, **kw)
        every = np.arange(model.n_cols)
        return dataclasses.replace(s, chosen=every, objective=float(model.values.sum()))


class WrongObjective(HighsBackend):
    name = "wrong-objective"

    def solve(self, model, options, **kw):
        s = super().solve(model, options, **kw)
        return dataclasses.replace(s, objective=s.objective + 1000.0)


class UnknownStatus(HighsBackend):
    name = "unknown-status"

    def solve(self, model, options, **kw):
        s = super().solve(model, options, **kw)
        return dataclasses.replace(s, status="optimal")


#: HiGHS's model status when LongSolve's long solve ended: kOptimal if SIGTERM had to wait for its end.
ENDED = []


class LongSolve(HighsBackend):
    """Solves a pairing MIP of seconds first, SIGTERM arriving a moment after it started."""

    name = "long-solve"

    def solve(self, model, options, **kw):
        from rpbench.backends import highs

        HighsBackend().solve(synthetic.pairing(20, seed=1), SolveOptions())
        h = highs._kept.highs["solve"]  # this thread's instance: the long solve below runs on it too
        hard = synthetic.pairing(1000, seed=1)
        threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)).start()
        try:
            HighsBackend().solve(hard, SolveOptions())
        finally:
            ENDED.append(h.getModelStatus().name)
        return super().solve(model, options, **kw)
'''


@pytest.fixture
def plug(tmp_path, monkeypatch):
    """``faultyplug`` importable (fresh for each test); failed-round dumps land in this test's cache."""
    folder = tmp_path / "plugins"
    folder.mkdir()
    (folder / "faultyplug.py").write_text(MODULE)
    forget("faultyplug")
    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    yield folder
    forget("faultyplug")


@pytest.mark.parametrize(
    "cls, fault",
    [
        ("NoModel", "build() returned None, not a RoundModel"),
        ("NanCost", "model 'nancost': value of column"),
        ("NanLater", "build() returned an invalid model: model 'mb': value of column 0 is nan; values must be finite"),
        ("OutOfRange", "build() returned an invalid model: model 'mb': column 0 has passenger"),
        ("KindsSwapped", "build() returned an invalid model: column 0 has kind"),
        ("WrongOrder", "but its model column serves order"),
        ("ShortDecoding", "RoundModel.fofo has"),
        ("BadMove", "reposition() target node 1000000000 is not a node index"),
    ],
)
def test_a_faulty_plugin_strategy_is_one_error_line(capsys, tmp_path, plug, cls, fault):
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", f"mb,faultyplug:{cls}", "--out", out)
    line = assert_one_error(code, err, f"(faultyplug.{cls}) round ", fault)
    assert line.startswith("rpbench: error: strategy '"), line
    assert_nothing_written(tmp_path, out)


def test_a_model_changed_to_nan_after_validation_never_reaches_highs(capsys, tmp_path, plug, monkeypatch):
    """A NaN objective sends HiGHS's simplex into a loop deaf to its time limit and to SIGTERM."""
    given = []
    solve = HighsBackend.solve

    def spy(self, model, options, **kw):
        given.append(bool(np.isfinite(model.values).all()))
        return solve(self, model, options, **kw)

    monkeypatch.setattr(HighsBackend, "solve", spy)
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "faultyplug:NanLater", "--out", out)
    assert_one_error(code, err, "strategy 'nanlater' (faultyplug.NanLater)", "is nan")
    assert False not in given
    assert_nothing_written(tmp_path, out)


@pytest.mark.parametrize(
    "cls, fault",
    [
        ("ReturnsNone", "returned None on 'mb', not a rpbench.model.Solution"),
        ("WrongLength", "chosen columns for the"),
        ("Fractional", "returned a fractional chosen column index"),
        ("Infeasible", "returned an infeasible solution of 'mb': row"),
        ("WrongObjective", "reports objective"),
        ("UnknownStatus", "returned status 'optimal' on 'mb', not one of Status.OPTIMAL"),
    ],
)
def test_a_faulty_plugin_backend_is_one_error_line(capsys, tmp_path, plug, cls, fault):
    preset = tmp_path / "faulty.toml"
    preset.write_text(f'backend = "faultyplug:{cls}"\n[options]\n')
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", preset, "--out", out)
    assert_one_error(code, err, f"backend 'faultyplug:{cls}' (faultyplug.{cls})", fault)
    assert_nothing_written(tmp_path, out)


def test_sigterm_ends_a_long_highs_solve(capsys, tmp_path, plug):
    """HiGHS's interrupt callback lets the CLI's SIGTERM handler run mid-solve: the solve never finishes."""
    preset = tmp_path / "long.toml"
    preset.write_text('backend = "faultyplug:LongSolve"\n[options]\n')
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--solver", preset, "--out", out)
    assert code == 143, err
    assert err.splitlines()[-1] == "rpbench: terminated (SIGTERM); nothing half-written was left"
    assert "Traceback" not in err and stdout == ""
    (status,) = sys.modules["faultyplug"].ENDED
    assert status != "kOptimal"  # interrupted mid-solve, not after it
    assert_nothing_written(tmp_path, out)
