"""Evaluation protocols: the built-in ones load; a bad one is one line."""

from __future__ import annotations

import pytest

from rpbench.exceptions import ParameterError
from rpbench.protocols import builtin_names, load_protocol


def test_the_builtin_protocols():
    assert {"peak-14", "peak-14-full", "toy-quick"} <= set(builtin_names())
    peak = load_protocol("peak-14")
    assert peak.seeds == (0, 1, 2, 3, 4) and peak.dates == "2017-05-01..2017-05-14" and peak.sample == 0.3
    assert peak.metrics[0] == "total_saving_km" and "bound" in peak.strategies
    assert peak.record()["digest"] == load_protocol("peak-14").record()["digest"]


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
