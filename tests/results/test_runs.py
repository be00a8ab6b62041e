"""Run labels and colours are read off the strategy classes and oracle runs."""

from __future__ import annotations

from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.results.runs import CLAIRVOYANT_MARK, run_color, run_label
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class


def test_labels_come_from_the_classes():
    assert run_label("fl-nd") == "FL-no_delay" and run_label("bound") == "Upper bound"
    for name in STRATEGY_REGISTRY:
        cls = strategy_class(name)
        mark = CLAIRVOYANT_MARK if getattr(cls, "clairvoyant", False) is True else ""
        assert run_label(name) == cls.label + mark and run_color(name) == cls.color
    assert run_label("hindsight") == "Hindsight (clairvoyant)"  # a strategy that reads the future says so
    for name, run in ORACLE_RUNS.items():
        assert run_label(name) == run.label and run_color(name) == run.color


def test_an_unknown_run_is_shown_under_its_own_name():
    assert run_label("mypkg.rules:Greedy") == "mypkg.rules:Greedy" and run_color("whatever") is None
