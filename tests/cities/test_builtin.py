"""Manhattan, built through the importer from its public data: what it keeps and drops, its speed from the
PNAS 2017 network's weekday times, and its scenarios."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.cities.builtin import MANHATTAN, builtin_city, hourly_speeds_kmh
from rpbench.cities.folder import read_city
from rpbench.scenarios import build_scenario

pytestmark = pytest.mark.manhattan


@pytest.fixture(scope="module")
def manhattan(manhattan_data_dir):
    return read_city(builtin_city("manhattan", manhattan_data_dir))


def test_manhattan_keeps_its_component_and_counts_what_it_drops(manhattan):
    net, trips = manhattan.record["network"], manhattan.record["trips"]
    assert (net["nodes_in"], net["arcs_in"], net["strong_components"]) == (4490, 9762, 90)  # SOURCE.md's counts
    assert (net["nodes_kept"], net["self_loops_dropped"], net["parallel_arcs_merged"]) == (4401, 10, 31)
    assert trips["rows"] == 98_235 and trips["time_resolution_s"] == 60.0 and trips["date"] is None
    assert trips["kept"] + sum(trips["dropped"].values()) == 98_235
    assert manhattan.network.n_nodes == 4401 and len(manhattan.request_s) == trips["kept"]


def test_a_second_call_takes_the_cached_folder(manhattan, manhattan_data_dir):
    assert builtin_city("manhattan", manhattan_data_dir) == manhattan.folder


def test_the_speed_is_the_pnas_networks_length_over_time_per_hour(manhattan, manhattan_data_dir):
    speeds = hourly_speeds_kmh(manhattan_data_dir / MANHATTAN.speeds)
    assert len(speeds) == 24 and manhattan.record["speed_kmh_by_hour"] == speeds
    assert 10 < speeds[8] < 15 and speeds[0] > speeds[8]  # slower in the morning peak than at midnight
    assert manhattan.speed_mps(8 * 3600, 9 * 3600) == pytest.approx(speeds[8] / 3.6)
    day = manhattan.speed_mps(0, 86400) * 3.6
    assert min(speeds) < day < max(speeds)
    assert day == pytest.approx(24 / sum(1 / s for s in speeds))  # the harmonic mean over the day


def test_the_peak_hour_scenario(manhattan_data_dir):
    sc = build_scenario("manhattan-peak", data_dir=manhattan_data_dir, seed=0)
    assert sc.name == "manhattan-peak" and sc.horizon_s == 3600.0 and sc.provenance["window"] == "08:00-09:00"
    in_hour = int(sc.provenance["trips_in_window"])
    assert len(sc.orders) == round(0.3 * in_hour) and len(sc.fleet) == round(0.25 * len(sc.orders))
    assert sc.params.speed_mps == pytest.approx(
        read_city(builtin_city("manhattan", manhattan_data_dir)).speed_mps(8 * 3600, 9 * 3600)
    )
    history = sc.demand.history
    assert history is not None and history.zone_m == 2000.0 and np.all(history.request_s < 3600)
