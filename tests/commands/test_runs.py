"""Command-line run arguments: ``--strategies`` and ``--opt RUN.KEY=VALUE`` into typed run entries."""

from __future__ import annotations

import pytest

from rpbench.commands._runs import parse_runs, split_option_key
from rpbench.exceptions import ParameterError


def test_opt_items_reach_their_run_typed():
    """Each ``--opt`` goes to the run its prefix names, converted by the declared type."""
    entries = parse_runs("mb,fl", ["fl.tau0_s=60", "mb.order_rule=min_then_check"])
    by_name = {e.name: e.options for e in entries}
    assert by_name["fl"].tau0_s == 60.0 and by_name["mb"].order_rule == "min_then_check"


def test_opt_for_a_run_not_listed_or_malformed_is_one_error():
    """A prefix that names no listed run, or an item without KEY=VALUE, fails in one line."""
    with pytest.raises(ParameterError, match="not in --strategies"):
        parse_runs("mb", ["fl.tau0_s=60"])
    with pytest.raises(ParameterError, match="expected RUN.KEY=VALUE"):
        parse_runs("mb", ["mb.order_rule"])


def test_the_longest_prefix_wins_for_names_with_dots():
    """Run names and ``module:Class`` sources may contain dots: the longest known prefix is the run."""
    assert split_option_key("mypkg.rules:Greedy.threshold", ["mypkg.rules:Greedy", "mb"]) == (
        "mypkg.rules:Greedy",
        "threshold",
    )
    assert split_option_key("fl.tau0_s", ["fl", "fl-nd"]) == ("fl", "tau0_s")
    assert split_option_key("nodot", ["fl"]) == ("nodot", "")
