"""The run specification: run names resolved once, typed options, one name per run, picklable."""

from __future__ import annotations

import pickle

import pytest

from rpbench.exceptions import ParameterError
from rpbench.oracle.runs import OracleOptions
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec, resolve_runs
from rpbench.strategies.rtv import RTVOptions


def test_names_are_case_insensitive_and_keep_their_order():
    """Built-in and offline names resolve in the order given, lower-cased."""
    assert [e.name for e in resolve_runs(["MB", " fl ", "oracle1"])] == ["mb", "fl", "oracle1"]
    assert [e.offline for e in resolve_runs(["mb", "bound"])] == [False, True]


def test_unknown_and_repeated_names_are_one_error_each():
    """An unknown name or a name given twice fails before anything runs."""
    with pytest.raises(ParameterError, match="unknown strategy 'fx'"):
        resolve_runs(["mb", "fx"])
    with pytest.raises(ParameterError, match="names 'mb' twice"):
        resolve_runs(["mb", "mb"])
    with pytest.raises(ParameterError, match="unknown strategy"):
        resolve_runs([" ", ""])


def test_of_types_the_options_of_each_run():
    """Options given as text or values are parsed by the run's declared options class."""
    spec = RunSpec.of("toy", ["rtv", "oracle1"], options={"rtv": {"rebalance": "true"}, "oracle1": {}})
    assert isinstance(spec.entry("rtv").options, RTVOptions) and spec.entry("rtv").options.rebalance is True
    assert isinstance(spec.entry("oracle1").options, OracleOptions)
    with pytest.raises(ParameterError, match="unknown option"):
        RunSpec.of("toy", ["rtv"], options={"rtv": {"no_such": 1}})
    with pytest.raises(ParameterError, match="not one of the runs"):
        RunSpec.of("toy", ["rtv"], options={"mb": {}})


def test_a_spec_pickles_and_moves_to_another_request():
    """Worker processes receive the spec as it is; a day or a sweep point changes only its request."""
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.2), ["mb", "fl"], preset="matching", strict=True)
    again = pickle.loads(pickle.dumps(spec))
    assert again == spec
    moved = spec.for_request(spec.request.replace(seed=3))
    assert moved.request.seed == 3 and moved.runs == spec.runs and moved.strict and moved.preset == "matching"
    assert [e.name for e in spec.simulated] == ["mb", "fl"] and spec.offline == []


def test_two_runs_under_one_name_are_refused():
    """The run name is a folder name: a spec refuses it twice."""
    (mb,) = resolve_runs(["mb"])
    with pytest.raises(ParameterError, match="appears twice"):
        RunSpec(request=ScenarioRequest("toy"), runs=(mb, mb))


# ------------------------------------------------------------------------------------------- variants
def test_a_variant_is_a_run_of_its_own_with_its_settings():
    from rpbench.commands._runs import parse_runs

    fl, variant, two = parse_runs("fl,fl@tau0_s=200,fl@tau0_s=200@accel=none", ["fl.accel=none"])
    assert (variant.name, variant.source, variant.settings) == ("fl@tau0_s=200", "fl", (("tau0_s", "200"),))
    assert variant.options.tau0_s == 200.0 and variant.options.accel == "anderson"  # --opt fl. is FL's only
    assert fl.options.accel == "none" and fl.options.tau0_s is None
    assert two.options.tau0_s == 200.0 and two.options.accel == "none"
    assert variant.label_of("FL") == "FL (tau0_s=200)" and fl.label_of("FL") == "FL"
    assert variant.color_of("tab:green") is None and fl.color_of("tab:green") == "tab:green"
    (more,) = parse_runs("fl@tau0_s=200", ["fl@tau0_s=200.rates=month"])  # --opt reaches a variant by its name
    assert more.options.rates == "month" and more.options.tau0_s == 200.0
    spec = RunSpec.of("toy", ["mb@order_rule=min_then_check"], options={"mb@order_rule=min_then_check": {}})
    assert spec.runs[0].options.order_rule == "min_then_check"


@pytest.mark.parametrize(
    ("strategies", "message"),
    [
        ("fl@tau0_s", "a variant's settings are OPTION=VALUE"),
        ("fl@tau0_s=a/b", "a variant's settings are OPTION=VALUE"),
        ("bound@window=x", "the offline runs take no variants"),
        ("fl@tau0_s=1@tau0_s=2", "sets an option twice"),
        ("fl@nope=1", "unknown option 'nope'"),
        ("fl@tau0_s=200,fl@tau0_s=200", "names 'fl@tau0_s=200' twice"),
    ],
)
def test_a_bad_variant_is_one_error(strategies, message):
    with pytest.raises(ParameterError, match=message):
        resolve_runs(strategies.split(","))


@pytest.mark.parametrize("budget", [0, -1.0, float("nan"), float("inf"), True, "0.5"])
def test_a_decision_budget_is_a_finite_number_of_seconds_above_zero(budget):
    with pytest.raises(ParameterError, match="must be a finite number of seconds > 0"):
        RunSpec.of("toy", ["mb"], decision_budget_s=budget)


def test_the_decision_budget_is_kept_per_day_and_point():
    spec = RunSpec.of("toy", ["mb"], decision_budget_s=0.5)
    assert spec.for_request(ScenarioRequest("toy", seed=2)).decision_budget_s == 0.5
    assert pickle.loads(pickle.dumps(spec)).decision_budget_s == 0.5
    assert RunSpec.of("toy", ["mb"]).decision_budget_s is None
