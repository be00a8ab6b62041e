"""Evaluation protocols: the built-in ones load; a bad one is one line."""

from __future__ import annotations

import pytest

from rpbench.exceptions import ParameterError
from rpbench.protocols import builtin_names, load_protocol
from rpbench.scenarios.request import parse_dates
from rpbench.strategies.value import ValueOptions

HAIKOU_DAYS = [f"2017-05-{d:02d}" for d in range(1, 15)]


def test_the_builtin_protocols():
    assert {"peak-14", "peak-14-full", "peak-vf", "peak-msa", "manhattan-peak", "toy-quick"} <= set(builtin_names())
    for name in builtin_names():
        assert load_protocol(name).name == name
    peak = load_protocol("peak-14")
    assert peak.seeds == (0, 1, 2, 3, 4) and peak.dates == "2017-05-01..2017-05-14" and peak.sample == 0.3
    assert peak.metrics[0] == "total_saving_km" and "bound" in peak.strategies
    assert peak.record()["digest"] == load_protocol("peak-14").record()["digest"]


@pytest.mark.parametrize("name", ["peak-vf", "peak-msa"])
def test_vf_protocols_test_on_days_vf_was_not_trained_on(name):
    protocol = load_protocol(name)
    tested = set(parse_dates(protocol.dates, HAIKOU_DAYS))
    trained = set(parse_dates(ValueOptions().train_dates, HAIKOU_DAYS))
    assert "vf" in protocol.strategies and tested and not tested & trained


def test_peak_msa_sets_msa_beside_the_forward_looking_and_clairvoyant_runs():
    protocol = load_protocol("peak-msa")
    assert protocol.strategies == ("mb", "fl", "vf", "msa", "fl-perfect", "hindsight", "bound")
    assert protocol.seeds == (0, 1, 2, 3, 4) and protocol.sample == 0.3 and protocol.dates == "2017-05-08..2017-05-14"
    assert protocol.metrics[:2] == ("total_saving_km", "competitive_ratio_bound")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('name = "x"', "missing field"),
        ('name="x"\nversion=1\nscenario="toy"\nseeds=[0,0]\nstrategies=["mb"]\nmetrics=["pairing_ratio"]', "distinct"),
        ('name="x"\nversion=1\nscenario="toy"\nseeds=[0]\nstrategies=["mb"]\nmetrics=["speed"]', "unknown metric"),
        (
            'name="x"\nversion=1\nscenario="toy"\nseeds=[0]\nstrategies=["mb"]\nmetrics=["pairing_ratio"]\nsede=1',
            "unknown field",
        ),
        (
            'name="x"\nversion="one"\nscenario="toy"\nseeds=[0]\nstrategies=["mb"]\nmetrics=["pairing_ratio"]',
            "wrong type",
        ),
        ("not toml [", "not valid TOML"),
    ],
)
def test_a_bad_protocol_is_one_line(tmp_path, text, message):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=message):
        load_protocol(str(path))


def test_an_unknown_protocol_names_the_builtin_ones():
    with pytest.raises(ParameterError, match="unknown protocol 'peak-99'.*peak-14"):
        load_protocol("peak-99")
