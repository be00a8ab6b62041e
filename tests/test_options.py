"""Typed run options: declared once per strategy, unknown names and bad values refused by name."""

from __future__ import annotations

import pytest

from rpbench.cli import main
from rpbench.commands._runs import parse_runs
from rpbench.exceptions import ParameterError
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.spec import options_class
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class
from rpbench.strategies.forward import ForwardOptions
from rpbench.strategies.rtv import RTVOptions

RUNS = list(STRATEGY_REGISTRY) + list(ORACLE_RUNS)


@pytest.mark.parametrize("name", RUNS)
def test_every_run_refuses_an_unknown_option_naming_the_known_ones(name):
    known = list(options_class(name)().as_dict())
    with pytest.raises(
        ParameterError, match=f"{name}: unknown option 'rebalence'; known options: {', '.join(known) or 'none'}$"
    ):
        parse_runs([name], [f"{name}.rebalence=true"])


@pytest.mark.parametrize("name", list(STRATEGY_REGISTRY))
def test_every_strategy_declares_label_and_defaults(name):
    cls = strategy_class(name)
    assert cls.label and cls.name == name
    options = cls.Options()
    assert cls(options).options == cls().options == options  # defaults parse to the same object
    assert set(cls.Options.help()) == set(options.as_dict())


def test_text_is_converted_by_the_declared_type():
    o = RTVOptions.parse("rtv", {"rebalance": "true", "rv_top_k": "3", "c_ko": "large", "objective": "gross"})
    assert o.rebalance is True and o.rv_top_k == 3 and o.c_ko == "large" and o.objective == "gross"
    assert RTVOptions.parse("rtv", {"c_ko": "1500"}).c_ko == 1500.0
    assert RTVOptions.parse("rtv", {"c_ko": "none", "rv_top_k": "none"}).rv_top_k is None
    f = ForwardOptions.parse("fl", {"tau0_s": "120,130", "mean_pickup_m": 900})
    assert f.tau0_s == (120.0, 130.0) and f.mean_pickup_m == 900.0


@pytest.mark.parametrize(
    "raw, message",
    [
        ({"rebalance": "maybe"}, "option rebalance = 'maybe' must be true/false"),
        ({"rebalance": 1}, "option rebalance = 1 must be true/false"),
        ({"rv_top_k": "2.5"}, "option rv_top_k = '2.5' must be an integer or none"),
        ({"rv_top_k": 0}, "option rv_top_k = 0 is out of range"),
        ({"c_ko": "huge"}, "option c_ko = 'huge' must be a finite number or none or one of large"),
        ({"c_ko": "nan"}, "option c_ko = 'nan' must be"),
        ({"objective": "profit"}, "option objective = 'profit' must be one of net, gross"),
        ({"reassign": True}, "reassign is not supported"),
    ],
)
def test_bad_values_are_refused_by_name(raw, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(")):
        RTVOptions.parse("rtv", raw)


def test_opt_must_name_a_run_in_the_list():
    with pytest.raises(ParameterError, match="run 'fl' is not in --strategies"):
        parse_runs(["mb"], ["fl.rates=month"])
    with pytest.raises(ParameterError, match="expected RUN.KEY=VALUE"):
        parse_runs(["rtv"], ["rtv"])


def test_cli_typo_exits_2_with_one_line(capsys, tmp_path):
    out = tmp_path / "never"
    code = main(
        [
            "run",
            "--scenario",
            "toy",
            "--strategies",
            "mb,rtv",
            "--opt",
            "rtv.rebalence=true",
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "unknown option 'rebalence'" in err[0] and "rebalance" in err[0]
    assert not out.exists()
