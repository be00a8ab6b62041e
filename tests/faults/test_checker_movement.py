"""Trajectories edited — odometers, times, nodes, NaN, offsets — each fails a named check."""

from __future__ import annotations

import numpy as np
import pytest

from faults import test_checker_helpers as helpers
from faults.test_checker_helpers import (
    assert_fails,
    edit_npz,
    events,
    joined_pair,
)
from rpbench import results

base, folder = helpers.base, helpers.folder  # fixtures (clean folders built once per module)


def traj_path(folder, run="mb"):
    return folder / "runs" / run / "trajectories.npz"


def middle_of_vehicle(z, v=3):
    lo, hi = z["vehicle_offsets"][v], z["vehicle_offsets"][v + 1]
    return int(lo + (hi - lo) // 2), int(hi)


def bump_odometer(z):
    k, _ = middle_of_vehicle(z)
    z["odo_m"][k] += 50.0


def shift_rest_of_odometer(z):
    k, hi = middle_of_vehicle(z)
    z["odo_m"][k:hi] += 100.0


def arrive_early(z):
    z["t_s"][5:] -= 3.0  # arrive at entry 5 three seconds too early


def time_backwards(z):
    k, _ = middle_of_vehicle(z)
    z["t_s"][k] = z["t_s"][k - 1] - 10.0


def leap_to_a_far_node(z):
    k, _ = middle_of_vehicle(z)
    z["node"][k] = (z["node"][k] + 70) % 144  # across the 12x12 grid: no arc leads there


def node_outside(z):
    k, _ = middle_of_vehicle(z)
    z["node"][k] = 10**6


def nan_at(key):
    def fn(z):
        k, _ = middle_of_vehicle(z, 5)
        z[key][k] = np.nan

    return fn


def inf_time(z):
    z["t_s"][-1] = np.inf


def broken_offsets(z):
    z["vehicle_offsets"][3] = z["vehicle_offsets"][2]


def vehicle_missing(z):
    z["vehicle_offsets"] = z["vehicle_offsets"][:-1].copy()
    z["vehicle_offsets"][-1] = len(z["node"])


def wrong_start(z):
    z["node"][z["vehicle_offsets"][4]] = (z["node"][z["vehicle_offsets"][4]] + 1) % 144


CASES = {
    "an odometer reading raised": (bump_odometer, "steps' odometer differs from the arc length"),
    "the odometer shifted from one entry on": (shift_rest_of_odometer, "steps' odometer differs from the arc length"),
    "arriving early (teleport)": (arrive_early, "arcs driven faster than"),
    "time running backwards": (time_backwards, "time runs backwards in trajectory entry"),
    "a leap to a far node": (leap_to_a_far_node, "steps are not network arcs"),
    "a node outside the network": (node_outside, "name a node outside the network"),
    "a NaN odometer": (nan_at("odo_m"), "have a non-finite time or odometer (NaN or inf)"),
    "a NaN time": (nan_at("t_s"), "have a non-finite time or odometer (NaN or inf)"),
    "an infinite time": (inf_time, "have a non-finite time or odometer (NaN or inf)"),
    "offsets that leave a vehicle without a trajectory": (broken_offsets, "do not split the entries"),
    "one trajectory too few": (vehicle_missing, "24 trajectories for 25 vehicles"),
    "a vehicle starting elsewhere": (wrong_start, "vehicle 4 does not start at its initial node"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_an_edited_trajectory_fails_movement(folder, case):
    fn, fragment = CASES[case]
    edit_npz(traj_path(folder), fn)
    assert_fails(folder, "movement", fragment, run="mb")


def test_a_shortened_shared_ride_fails_the_bound_certificate(folder):
    """5 km less occupied driving after a pair's last drop-off: its saving exceeds the bound's edge weight."""
    ev = events(folder, "mb")
    joining, first, _ = joined_pair(folder)
    drops = ev[(ev["event"] == "dropoff") & ev["order"].isin([joining, first])]
    last = drops.sort_values("t_s").iloc[-1]
    traj = results.load_trajectories(traj_path(folder))
    lo, hi = traj["vehicle_offsets"][int(last["vehicle"])], traj["vehicle_offsets"][int(last["vehicle"]) + 1]
    k = (
        lo
        + np.flatnonzero((np.abs(traj["t_s"][lo:hi] - last["t_s"]) < 1e-6) & (traj["node"][lo:hi] == last["node"]))[0]
    )
    traj["odo_m"][k:hi] -= 5000.0
    results.save_trajectories(traj_path(folder), traj)
    found = assert_fails(folder, "bound-certificate", "exceeds the bound's edge weight", run="mb")
    assert "movement" in found and "kpi" in found
