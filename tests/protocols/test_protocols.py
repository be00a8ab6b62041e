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


GOOD = {
    "name": '"x"',
    "version": "1",
    "scenario": '"toy"',
    "seeds": "[0, 1]",
    "strategies": '["mb", "bound"]',
    "metrics": '["pairing_ratio"]',
}


def protocol_text(**changes: str | None) -> str:
    """A valid protocol's TOML with fields changed (a value of None drops the field)."""
    fields = {**GOOD, **changes}
    return "\n".join(f"{k} = {v}" for k, v in fields.items() if v is not None and k != "bootstrap") + (
        f"\n[bootstrap]\n{changes['bootstrap']}\n" if changes.get("bootstrap") else "\n"
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('name = "x"', "missing field"),
        (protocol_text(seeds="[0, 0]"), "seeds must be distinct: 0 appears more than once"),
        (protocol_text(metrics='["speed"]'), "unknown metric"),
        (protocol_text() + "sede = 1\n", "unknown field"),
        (protocol_text(version='"one"'), "version must be a whole number, not 'one'"),
        ("not toml [", "not valid TOML"),
        # nothing is coerced: a string is not a list, a float not an integer, a bool not a number
        (protocol_text(seeds='"012"'), "seeds must be an array"),
        (protocol_text(seeds="[0.7]"), "seeds must be whole numbers"),
        (protocol_text(seeds="[true]"), "seeds must be whole numbers"),
        (protocol_text(seeds="[-1]"), "seeds must be >= 0"),
        (protocol_text(seeds="[]"), "seeds must not be empty"),
        (protocol_text(version="1.9"), "version must be a whole number, not 1.9"),
        (protocol_text(version="0"), "version must be in 1"),
        (protocol_text(sample="true"), "sample must be a finite number, not True"),
        (protocol_text(sample="1.5"), r"sample must be in \(0, 1\]"),
        (protocol_text(sample="nan"), "sample must be a finite number"),
        (protocol_text(strategies='"mb"'), "strategies must be an array"),
        (protocol_text(strategies='["mb", "mb"]'), "strategies must be distinct"),
        (protocol_text(strategies='["mb", ""]'), "strategies must be non-empty strings"),
        (protocol_text(metrics='["pairing_ratio", "pairing_ratio"]'), "metrics must be distinct"),
        (protocol_text(metrics='["saving_over_oracle1"]'), "divides by the run 'oracle1'"),
        (protocol_text(strategies='["mb"]', metrics='["competitive_ratio_bound"]'), "divides by the run 'bound'"),
        (protocol_text(name='""'), "name '' is not a plain name"),
        (protocol_text(name='"a/b"'), "name 'a/b' is not a plain name"),
        (protocol_text(name='"../../.."'), "is not a plain name"),
        (protocol_text(name='".hidden"'), "is not a plain name"),
        (protocol_text(name='"a\\nb"'), "is not a plain name"),
        (protocol_text(name="3"), "name must be a string, not 3"),
        (protocol_text(dates="[1]"), "dates must be a string"),
        (protocol_text(bootstrap="seed = -1"), "bootstrap.seed must be in 0"),
        (protocol_text(bootstrap="resamples = 2.5"), "bootstrap.resamples must be a whole number"),
        (protocol_text(bootstrap="level = 1.0"), r"bootstrap.level must be in \[0.5, 1\)"),
        (protocol_text(bootstrap="levle = 0.9"), "unknown bootstrap field"),
        (protocol_text() + "bootstrap = 3\n", "bootstrap must be a table"),
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
