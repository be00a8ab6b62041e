"""The ``city`` scenario: a window of an imported city's day, sampled, its minute clock spread, the hour
before as the demand history, the city's speed; run end to end and checked."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from cities.conftest import grid_graph

from rpbench.check import check_folder
from rpbench.cities.folder import CITY_JSON
from rpbench.cities.importer import Sources, import_city
from rpbench.cities.trips import TripOptions
from rpbench.exceptions import NoOrdersError, ParameterError
from rpbench.harness.comparison import run_comparison
from rpbench.scenarios import ScenarioRequest, build_scenario
from rpbench.scenarios.city import parse_window
from rpbench.spec import RunSpec


@pytest.fixture
def city(tmp_path):
    """A grid city with 400 trips over 06:00-10:00 recorded to the minute, importable by folder path."""
    import networkx as nx

    graph = tmp_path / "grid.graphml"
    nx.write_graphml(grid_graph(), graph)
    rng = np.random.default_rng(3)
    ids = np.array([1000 + k for k in range(25)])
    origin = rng.choice(ids, 400)
    destination = (origin - 1000 + rng.integers(1, 25, 400)) % 25 + 1000  # never the origin
    minutes = np.sort(rng.integers(6 * 60, 10 * 60, 400))
    pd.DataFrame({"minute": minutes, "o": origin, "d": destination}).to_csv(tmp_path / "trips.csv", index=False)
    options = TripOptions(columns={"time": "minute", "origin_node": "o", "destination_node": "d"}, time_unit="min")
    made = import_city("grid", Sources(trips=tmp_path / "trips.csv", network=graph), options, tmp_path / "grid")
    return made.folder, minutes


def test_a_window_holds_its_trips_spread_inside_their_minutes(city):
    folder, minutes = city
    sc = build_scenario("city", city=str(folder), window="08:00-09:00", seed=1)
    inside = (minutes >= 480) & (minutes < 540)
    assert len(sc.orders) == inside.sum() and sc.horizon_s == 3600.0
    assert np.all((sc.orders.request_s >= 0) & (sc.orders.request_s < 3600))
    # each request lies in its recorded minute, not on the minute
    assert np.array_equal(np.sort(sc.orders.request_s // 60), np.sort(minutes[inside] - 480))
    assert np.mean(sc.orders.request_s % 60 > 0) > 0.9
    again = build_scenario("city", city=str(folder), window="08:00-09:00", seed=1)
    assert np.array_equal(again.orders.request_s, sc.orders.request_s)  # seeded
    assert sc.provenance["window"] == "08:00-09:00" and sc.provenance["city"] == "grid" and not sc.synthetic


def test_the_history_is_the_hour_before_never_the_window(city):
    folder, minutes = city
    sc = build_scenario("city", city=str(folder), window="08:00-10:00")
    history = sc.demand.history
    assert history is not None and history.days == 1
    before = (minutes >= 420) & (minutes < 540)  # 07:00-09:00, moved one hour on
    assert len(history.request_s) == before.sum()
    assert np.all((history.request_s >= 0) & (history.request_s < 7200))
    assert sc.online_view().demand.history is history


def test_sampling_and_the_fleet_follow_the_paper(city):
    folder, minutes = city
    full = build_scenario("city", city=str(folder), window="08:00-09:00")
    half = build_scenario("city", city=str(folder), window="08:00-09:00", sample=0.5)
    assert len(half.orders) == round(0.5 * len(full.orders)) and len(full.fleet) == round(0.25 * len(full.orders))
    day = build_scenario("city", city=str(folder), window="06:00-10:00")
    assert day.fleet.online_count is not None and len(day.fleet.online_count) == 4  # follows hourly demand


def test_the_city_speed_is_the_default_and_param_overrides_it(city):
    folder, _ = city
    record = json.loads((folder / CITY_JSON).read_text())
    record["speed_kmh"] = 18.0
    (folder / CITY_JSON).write_text(json.dumps(record))
    assert build_scenario("city", city=str(folder)).params.speed_mps == pytest.approx(5.0)
    faster = build_scenario("city", city=str(folder), param_overrides={"speed_mps": 10.0})
    assert faster.params.speed_mps == 10.0


def test_bad_windows_cities_and_options_are_one_line(city, tmp_path):
    folder, _ = city
    for text in ("8-9", "09:00-08:00", "23:00-25:00", "08:60-09:00"):
        with pytest.raises(ParameterError, match="--window"):
            parse_window(text)
    with pytest.raises(ParameterError, match="needs --city NAME"):
        build_scenario("city")
    with pytest.raises(ParameterError, match="is not a city's day"):
        build_scenario("toy", window="08:00-09:00")
    with pytest.raises(ParameterError, match="has no date to choose"):
        build_scenario("city", city=str(folder), date="2017-05-01")
    with pytest.raises(NoOrdersError, match="the 02:00-03:00 window of city 'grid'"):
        build_scenario("city", city=str(folder), window="02:00-03:00")
    with pytest.raises(Exception, match="city 'nowhere' is neither a city folder"):
        build_scenario("city", city="nowhere")


def test_a_city_run_is_written_recorded_and_checked(city, tmp_path):
    folder, _ = city
    request = ScenarioRequest("city", city=str(folder), window="08:00-09:00", seed=2)
    assert request.meta()["city"] == str(folder) and request.meta()["window"] == "08:00-09:00"
    assert "city" not in ScenarioRequest("toy").meta()  # a Haikou or toy folder records what it did before
    outcome = run_comparison(RunSpec.of(request, ["mb", "fl", "hindsight", "bound"]), tmp_path / "run", progress=False)
    assert outcome.table.loc["total_saving_km", "bound"] >= outcome.table.loc["total_saving_km", "hindsight"]
    meta = json.loads((outcome.folder / "meta.json").read_text())
    assert meta["scenario"]["provenance"]["city"] == "grid" and meta["runs"]["fl"]["clairvoyant"] is False
    checks = check_folder(outcome.folder)
    assert checks and all(not rc.violations for rc in checks)


def test_vf_trains_on_the_hours_before_the_window_and_never_on_it(city):
    from rpbench.valuefn.training import Settings, held_out_problem, training_record, training_scenarios

    folder, _ = city
    test = build_scenario("city", city=str(folder), window="08:00-09:00")
    runs = training_scenarios(test, "", (100,), hours=3)
    assert [r.provenance["window"] for r in runs] == ["06:00-07:00", "07:00-08:00"]  # 05:00-06:00 has no trip
    assert held_out_problem(test, training_record(runs, Settings())) is None
    earlier = build_scenario("city", city=str(folder), window="07:30-08:30")
    assert "overlaps the window 07:30-08:30" in held_out_problem(earlier, training_record(runs, Settings()))
    with pytest.raises(ParameterError, match="hold no trips of the city's day to train on"):
        training_scenarios(build_scenario("city", city=str(folder), window="06:00-07:00"), "", (100,), hours=1)
