"""Conformance suite: every preset in solvers/ on hand-checkable models with known optima.

Values are integral, so objectives are compared exactly.  Each test runs
once per preset (``preset`` fixture); a preset is skipped only when its
library is missing.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from rpbench.model import AssignmentModel, PairingModel, Status, TripPackingModel

from .brute import brute_force


def check(model, backend, options, objective, chosen=None, status=Status.OPTIMAL):
    sol = backend.solve(model, options)
    assert sol.status is status, sol.message
    assert sol.backend == backend.name
    assert model.violations(sol.chosen) == []
    assert sol.objective == objective
    if chosen is not None:
        assert sol.chosen.tolist() == sorted(chosen)
    if status is Status.OPTIMAL:
        assert sol.bound == objective and sol.gap == 0.0
    assert min(sol.build_s, sol.solve_s, sol.extract_s) >= 0.0
    return sol


# ------------------------------------------------------------------ empty models
@pytest.mark.parametrize(
    "model",
    [
        AssignmentModel(0, 0, [], [], []),
        AssignmentModel(0, 3, [], [], []),
        TripPackingModel(0, 0, [], [], [], []),
        TripPackingModel(2, 2, [], [], [], []),
        PairingModel(0, [], [], []),
        PairingModel(5, [], [], [], objective="cardinality_then_weight"),
    ],
    ids=["assign-0x0", "assign-0x3", "pack-0x0", "pack-2x2-nocols", "pair-0", "pair-5-nocols"],
)
def test_empty_models_are_solved_by_nothing(preset, model):
    _, backend, options = preset
    check(model, backend, options, 0.0, chosen=[])


# ------------------------------------------------------------------ assignment
def test_passenger_whose_best_option_is_to_wait(preset):
    _, backend, options = preset
    # passenger 0: vehicle 0 worth -5, waiting worth -2 -> waits
    m = AssignmentModel(1, 1, [0, 0], [0, -1], [-5, -2])
    check(m, backend, options, -2.0, chosen=[1])


def test_passenger_with_no_feasible_vehicle_waits(preset):
    _, backend, options = preset
    # passenger 1 has only its wait option; passenger 0 takes the vehicle
    m = AssignmentModel(2, 1, [0, 0, 1], [0, -1, -1], [-1, -9, -7])
    check(m, backend, options, -8.0, chosen=[0, 2])


def test_one_vehicle_two_passengers_goes_to_the_better_one(preset):
    _, backend, options = preset
    m = AssignmentModel(2, 1, [0, 0, 1, 1], [0, -1, 0, -1], [-3, -10, -4, -5])
    # 0 rides (-3) + 1 waits (-5) = -8  beats  0 waits (-10) + 1 rides (-4) = -14
    check(m, backend, options, -8.0, chosen=[0, 3])


def test_assignment_without_wait_options_is_infeasible_when_vehicles_are_short(preset):
    _, backend, options = preset
    m = AssignmentModel(2, 1, [0, 1], [0, 0], [-1, -2])
    sol = backend.solve(m, options)
    assert sol.status is Status.INFEASIBLE and sol.cardinality == 0


def test_mandatory_passengers_are_served_when_possible(preset):
    _, backend, options = preset
    # no wait options: the only perfect assignment is 0->1, 1->0 (cost -20) though 0->0 alone is cheaper
    m = AssignmentModel(2, 2, [0, 0, 1], [0, 1, 0], [-1, -10, -10])
    check(m, backend, options, -20.0, chosen=[1, 2])


def test_ties_return_one_optimal_assignment(preset):
    _, backend, options = preset
    P, V = 3, 3
    cp, cv = np.repeat(np.arange(P), V), np.tile(np.arange(V), P)
    m = AssignmentModel(P, V, np.r_[cp, np.arange(P)], np.r_[cv, -np.ones(P, int)], np.r_[np.full(P * V, -4), [-9] * P])
    sol = check(m, backend, options, -12.0)
    assert sol.cardinality == 3


def test_negative_values_assignment_takes_the_least_bad(preset):
    _, backend, options = preset
    m = AssignmentModel(2, 2, [0, 0, 1, 1], [0, 1, 0, 1], [-100, -1, -2, -300])
    check(m, backend, options, -3.0, chosen=[1, 2])


# ------------------------------------------------------------------ pairing
TRIANGLE = PairingModel(3, [0, 0, 1], [1, 2, 2], [1, 1, 1])


def test_triangle_lp_relaxation_is_fractional():
    # the reason pairing needs an integral method: the LP gives 1.5 with every y = 1/2
    A = TRIANGLE.incidence().toarray()
    lp = linprog(-TRIANGLE.values, A_ub=A, b_ub=np.ones(3), bounds=(0, 1), method="highs")
    assert lp.status == 0 and -lp.fun == pytest.approx(1.5) and np.allclose(lp.x, 0.5)


@pytest.mark.parametrize("objective", ["weight", "cardinality_then_weight"])
def test_unit_triangle_has_optimum_one(preset, objective):
    _, backend, options = preset
    m = PairingModel(3, [0, 0, 1], [1, 2, 2], [1, 1, 1], objective=objective)
    sol = check(m, backend, options, 1.0)
    assert sol.cardinality == 1


def test_oracle2_prefers_more_pairs_over_more_weight(preset):
    _, backend, options = preset
    # path 0-1-2-3 valued 1, 10, 1: Oracle-1 takes the middle (10), Oracle-2 the two ends (2 pairs, 2)
    a, b, v = [0, 1, 2], [1, 2, 3], [1, 10, 1]
    check(PairingModel(4, a, b, v), backend, options, 10.0, chosen=[1])
    check(PairingModel(4, a, b, v, objective="cardinality_then_weight"), backend, options, 2.0, chosen=[0, 2])


def test_oracle2_breaks_cardinality_ties_by_weight_and_uses_negative_pairs(preset):
    _, backend, options = preset
    # the 4-cycle 0-1-2-3-0 has two perfect matchings, {01, 23} = 6 - 3 = 3 and {12, 03} = 4 + 1 = 5;
    # Oracle-1 takes 01 alone (6).  The isolated pair (4, 5) is worth -2: Oracle-2 takes it for the pair
    a, b, v = [0, 1, 2, 0, 4], [1, 2, 3, 3, 5], [6, 4, -3, 1, -2]
    check(PairingModel(6, a, b, v), backend, options, 6.0, chosen=[0])
    sol = check(PairingModel(6, a, b, v, objective="cardinality_then_weight"), backend, options, 3.0, chosen=[1, 3, 4])
    assert sol.cardinality == 3


def test_pairing_with_only_negative_values_is_empty_for_oracle1(preset):
    _, backend, options = preset
    check(PairingModel(4, [0, 1, 2], [1, 2, 3], [-1, -5, -2]), backend, options, 0.0, chosen=[])
    check(
        PairingModel(4, [0, 1, 2], [1, 2, 3], [-1, -5, -2], objective="cardinality_then_weight"),
        backend,
        options,
        -3.0,
        chosen=[0, 2],
    )


# ------------------------------------------------------------------ trip packing
def test_two_request_trip_beats_two_single_trips(preset):
    _, backend, options = preset
    # singles r0@v0 = 3, r1@v1 = 3 (total 6) versus the pooled trip {r0, r1}@v0 = 7
    m = TripPackingModel(2, 2, [0, 1, 0], [0, 1, 0], [-1, -1, 1], [3, 3, 7])
    check(m, backend, options, 7.0, chosen=[2])
    m = TripPackingModel(2, 2, [0, 1, 0], [0, 1, 0], [-1, -1, 1], [3, 3, 5])
    check(m, backend, options, 6.0, chosen=[0, 1])


def test_trip_packing_respects_vehicles_and_requests(preset):
    _, backend, options = preset
    # one vehicle: the best single column wins; negative columns are left out
    m = TripPackingModel(3, 1, [0, 0, 0, 0], [0, 1, 2, 0], [-1, -1, -1, 1], [4, 6, -1, 9])
    check(m, backend, options, 9.0, chosen=[3])
    m = TripPackingModel(2, 2, [0, 1], [0, 1], [-1, -1], [-4, -2])
    check(m, backend, options, 0.0, chosen=[])


# ------------------------------------------------------------------ determinism and brute force
def test_identical_input_gives_identical_output(preset):
    _, backend, options = preset
    rng = np.random.default_rng(7)
    P, V = 6, 5
    cp, cv = np.repeat(np.arange(P), V), np.tile(np.arange(V), P)
    values = rng.integers(-3, 1, P * V) * 1000  # many ties
    m = AssignmentModel(P, V, np.r_[cp, np.arange(P)], np.r_[cv, -np.ones(P, int)], np.r_[values, [-2500] * P])
    first, second = backend.solve(m, options), backend.solve(m, options)
    assert first.chosen.tolist() == second.chosen.tolist() and first.objective == second.objective


def test_hand_models_match_brute_force():
    models = [
        TRIANGLE,
        PairingModel(4, [0, 1, 2], [1, 2, 3], [1, 10, 1], objective="cardinality_then_weight"),
        TripPackingModel(2, 2, [0, 1, 0], [0, 1, 0], [-1, -1, 1], [3, 3, 7]),
        AssignmentModel(2, 2, [0, 0, 1], [0, 1, 0], [-1, -10, -10]),
    ]
    assert [brute_force(m)[0] for m in models] == [1.0, 2.0, 7.0, -20.0]
    assert brute_force(AssignmentModel(2, 1, [0, 1], [0, 0], [-1, -2])) is None
