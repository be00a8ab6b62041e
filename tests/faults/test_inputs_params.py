"""Absurd parameters (``--param NAME=VALUE``): one line and exit status 2 before any simulation, no --out.

The bounds are the ones documented in :class:`rpbench.scenarios.base.Params`; the paper's defaults,
every value of the sweeps and every value the other tests use stay valid.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from rpbench.exceptions import ParameterError
from rpbench.harness.sweep import SWEEPS, expand
from rpbench.scenarios.base import Params

from .test_inputs_helpers import TOY_RUN, cli_error


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


ABSURD = [
    ("speed_mps", "1e-300", "outside its sane range [0.1, 100] m/s"),
    ("speed_mps", "1e300", "outside its sane range [0.1, 100] m/s"),
    ("speed_mps", "0.01", "outside its sane range [0.1, 100] m/s"),
    ("speed_mps", "inf", "is not a finite number"),
    ("dt_s", "1e-9", "outside its sane range [0.1, 3600] s"),
    ("dt_s", "1e300", "outside its sane range [0.1, 3600] s"),
    ("dt_s", "nan", "is not a finite number"),
    ("max_pickup_m", "1e300", "outside its sane range (0, 1e+06] m"),
    ("max_detour_m", "2e6", "outside its sane range (0, 1e+06] m"),
    ("planner_patience_s", "1e300", "outside its sane range [1, 86400] s"),
    ("patience_mean_s", "0.5", "outside its sane range [1, 86400] s"),
    ("patience_sd_s", "1e300", "outside its sane range [0, 86400] s"),
    ("patience_floor_s", "1e9", "outside its sane range [0, 86400] s"),
    ("vehicles_per_100_orders", "1e300", "outside its sane range (0, 1000]"),
    ("alpha", "1e300", "outside its sane range (0, 10]"),
    ("fare_solo_cny_per_km", "1e300", "outside its sane range [0, 1000] CNY/km"),
    ("driver_pay_cny_per_km", "-1", "must be >= 0"),
    ("response_rate", "1.5", "must lie in [0, 1]"),
]


@pytest.mark.parametrize("name, value, message", ABSURD, ids=[f"{n}={v}" for n, v, _ in ABSURD])
def test_absurd_parameter_is_one_line_before_any_run(capsys, tmp_path, name, value, message):
    out = tmp_path / "results"
    line = cli_error(capsys, *TOY_RUN, "--param", f"{name}={value}", "--out", out)
    assert line.startswith(f"parameter {name} = ") and message in line
    assert not out.exists()


def test_paper_defaults_and_every_sweep_value_pass():
    Params()
    for spec in SWEEPS.values():
        for point in expand(spec.parameter, spec.values):
            Params().replace(**point.overrides)


@pytest.mark.parametrize(
    "name, values",
    [
        ("dt_s", (0.1, 2, 10, 30, 60, 3600)),
        ("speed_mps", (0.1, 30 / 3.6, 100)),
        ("max_detour_m", (1e-3, 500.0, 3000.0, 1e6)),
        ("max_pickup_m", (400.0, 700.0, 1e6)),
        ("patience_mean_s", (1, 40, 60, 300, 600, 86400)),
        ("planner_patience_s", (1, 30, 180, 86400)),
        ("response_rate", (0.0, 0.1, 0.9, 1.0)),
        ("vehicles_per_100_orders", (10, 25, 1000)),
        ("alpha", (1.01, 2.0, 10.0)),
    ],
)
def test_values_the_tests_and_the_paper_use_stay_valid(name, values):
    for value in values:
        assert getattr(Params().replace(**{name: value}), name) == value


@pytest.mark.parametrize("name, value", list(itertools.product(["dt_s", "speed_mps", "alpha"], [True, "10", None])))
def test_non_numbers_are_refused_in_code_too(name, value):
    with pytest.raises(ParameterError, match=f"{name} = .* is not a finite number"):
        Params().replace(**{name: value})


SWEEP = ("sweep", "--scenario", "toy", "--sample", "0.1", "--strategies", "np", "--workers", "1")


@pytest.mark.parametrize(
    "argv, message",
    [
        (("--over", "dt_s=20,30", "--param", "dt_s=5"), "--param dt_s conflicts with the sweep over dt_s"),
        (("--over", "dt=20,30", "--param", "dt_s=5"), "--param dt_s conflicts with the sweep over dt"),
        (("interval", "--param", "dt_s=5"), "--param dt_s conflicts with the sweep over dt"),
        (("--over", "K=60,90", "--param", "patience_mean_s=80"), "--param patience_mean_s conflicts"),
        (("--over", "dt=20,30", "--param", "dt_s=1e300"), "parameter dt_s = 1e+300 is outside its sane range"),
    ],
)
def test_a_param_the_sweep_sets_is_one_line_before_any_run(capsys, tmp_path, argv, message):
    out = tmp_path / "sweep"
    line = cli_error(capsys, *SWEEP, *argv, "--out", out)
    assert message in line, line
    assert not out.exists()


def test_a_param_the_sweep_does_not_set_still_applies():
    from rpbench.harness.sweep import expand

    for point in expand("dt", (20.0, 30.0)):
        point.refuse_overrides({"max_detour_m": 500.0})  # another parameter: no conflict
