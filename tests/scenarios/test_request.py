"""The frozen scenario request: build, what a folder records, and --dates for every dated scenario."""

from __future__ import annotations

import pickle

import pytest

from rpbench.exceptions import ParameterError
from rpbench.scenarios import ScenarioRequest


def test_peak_dates(two_day_data):
    request = ScenarioRequest("haikou-peak", data_dir=str(two_day_data))
    assert request.dates("2017-04-01..2017-05-31") == ["2017-05-01", "2017-05-02"]
    assert request.dates("2017-05-02") == ["2017-05-02"]
    with pytest.raises(ParameterError, match="no data for 2017-05-09"):
        request.dates("2017-05-01,2017-05-09")
    with pytest.raises(ParameterError, match="ends before it starts"):
        request.dates("2017-05-02..2017-05-01")


def test_undated_scenarios_refuse_dates():
    with pytest.raises(ParameterError, match="scenario 'toy' has no dates"):
        ScenarioRequest("toy").dates("2017-05-01")


def test_unknown_scenario_fails_at_once():
    with pytest.raises(ParameterError, match="unknown scenario 'tiny'"):
        ScenarioRequest("tiny")


def test_build_meta_and_overrides():
    request = ScenarioRequest("toy", sample=0.2, seed=3, params=(("dt_s", 30.0),))
    scenario = request.build()
    assert scenario.params.dt_s == 30.0 and scenario.seed == 3
    assert request.meta() == {
        "date": None,
        "sample": 0.2,
        "seed": 3,
        "params": {"dt_s": 30.0},
        "fleet_placement": "order_origins",
    }
    more = request.with_overrides({"dt_s": 10.0, "max_detour_m": 2000.0})
    assert more.overrides == {"dt_s": 10.0, "max_detour_m": 2000.0} and request.overrides == {"dt_s": 30.0}
    assert pickle.loads(pickle.dumps(more)) == more  # crosses to worker processes
    # overrides are kept sorted, so the same overrides make equal requests
    assert ScenarioRequest("toy", params=(("b", 1.0), ("a", 2.0))) == ScenarioRequest(
        "toy", params=(("a", 2.0), ("b", 1.0))
    )
