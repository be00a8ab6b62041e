"""Strategies that read the future: refused unless declared, marked where declared; FL's rates.

A plug-in module written to a temporary folder on ``sys.path`` runs through ``rpbench run`` as
``module:Class``; FL's ``rates=scenario`` counts the day's own orders, so its run is clairvoyant.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from plugin_helpers import forget

from rpbench import plugins
from rpbench.backends import load_preset
from rpbench.cli import main
from rpbench.scenarios import build_scenario
from rpbench.scenarios.base import Demand
from rpbench.sim.simulator import Simulator
from rpbench.strategies import make_strategy

MODULE = '''
from rpbench.strategies.myopic import MyopicBatch


class Peeker(MyopicBatch):
    """MB that counts the day's orders before the first round."""

    name = "peek"
    label = "Peek"

    def prepare(self, scenario):
        self.n_orders = len(scenario.orders)


class Seer(Peeker):
    name = "seer"
    label = "Seer"
    clairvoyant = True
'''
#: FL without its MB calibration run (τ_0 and l̄ given).
FIXED = {"tau0_s": 60.0, "mean_pickup_m": 900.0}


@pytest.fixture
def plugin_dir(tmp_path, monkeypatch):
    folder = tmp_path / "plugins"
    folder.mkdir()
    (folder / "peekmod.py").write_text(MODULE)
    forget("peekmod")
    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.syspath_prepend(str(folder))
    yield folder
    forget("peekmod")


def run(*args: str) -> int:
    return main(["run", "--scenario", "toy", "--sample", "0.1", "--no-progress", *args])


def test_an_online_plugin_reading_the_orders_exits_2_in_one_line(plugin_dir, tmp_path, capsys):
    out = tmp_path / "never"
    assert run("--strategies", "mb,peekmod:Peeker", "--out", str(out)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    expected = (
        "rpbench: error: strategy 'peek' (peekmod.Peeker) read the scenario's orders before they were revealed: "
        "online strategies see orders only as they are revealed in RoundState; declare `clairvoyant = True` to "
        "read the future"
    )
    assert [line for line in err if line.startswith("rpbench: error")] == err[-1:] == [expected]
    assert not any("Traceback" in line for line in err) and not out.exists()


@pytest.mark.slow
def test_clairvoyant_runs_are_recorded_and_labelled(plugin_dir, tmp_path, capsys):
    """A declared clairvoyant plug-in and FL with rates=scenario run; meta.json and the report say so."""
    out = tmp_path / "run"
    opts = [f"--opt=fl.{k}={v}" for k, v in FIXED.items()]
    code = run("--strategies", "mb,peekmod:Seer,fl", "--opt", "fl.rates=scenario", *opts, "--out", str(out))
    assert code == 0, capsys.readouterr().err
    meta = json.loads((out / "meta.json").read_text())
    assert {r: meta["runs"][r]["clairvoyant"] for r in ("mb", "seer", "fl")} == {"mb": False, "seer": True, "fl": True}
    assert meta["runs"]["seer"]["label"] == "Seer"  # the record keeps the class's label; reports mark it
    report = (out / "report.md").read_text()
    assert "| Metric | MB | Seer (clairvoyant) | FL (clairvoyant) |" in report
    assert main(["check", str(out)]) == 0


def moved_destination(scenario):
    o = scenario.orders
    destination = o.destination.copy()
    destination[0] = (destination[0] + 1) % scenario.network.n_nodes
    return dataclasses.replace(scenario, orders=dataclasses.replace(o, destination=destination))


def prediction_inputs(scenario, **options):
    """The rates FL's prediction was fed in a simulation of ``scenario``, and whether the run was clairvoyant."""
    fl = make_strategy("fl", **FIXED, **options)
    sim = Simulator(scenario, fl, load_preset("highs")).run()
    (prediction,) = fl.predictions
    rates = prediction.rates
    return (rates.origin, rates.destination, rates.rate_per_s), sim.clairvoyant


def same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def test_fl_on_the_toy_city_gets_no_realised_order_counts():
    """The toy city's FL predicts from its generator's past days: changing one of the day's orders after the
    fact does not change what the prediction is fed (from the day's own orders it does: clairvoyant)."""
    toy = build_scenario("toy", sample=0.1, seed=6)
    moved = moved_destination(toy)
    online, clairvoyant = prediction_inputs(toy)
    again, _ = prediction_inputs(moved)
    assert not clairvoyant
    assert same(online, again)
    own, clairvoyant = prediction_inputs(toy, rates="scenario")
    own_moved, _ = prediction_inputs(moved, rates="scenario")
    assert clairvoyant
    assert not same(own, own_moved)


@pytest.mark.parametrize("name", ["fl", "fl-nd"])
def test_fl_is_clairvoyant_when_it_counts_the_days_orders(name):
    toy = build_scenario("toy", sample=0.1)
    no_history = dataclasses.replace(toy, demand=Demand())  # as the 2017-07-01 trace: nothing but the day
    for rates, options_say, on_toy, on_bare in [
        ("auto", False, False, True),
        ("history", False, False, False),
        ("month", False, False, False),
        ("scenario", True, True, True),
    ]:
        fl = make_strategy(name, rates=rates)
        assert fl.clairvoyant is options_say, rates
        assert fl.describe()["clairvoyant"] is options_say
        assert (fl.clairvoyant_on(toy), fl.clairvoyant_on(no_history)) == (on_toy, on_bare), rates
    assert not any(make_strategy(s).clairvoyant for s in ("np", "mb", "rtv", "vf"))
