"""The one entry point: support checked, the answer verified once (feasible, or honestly infeasible)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.backends import Backend, Preset, SolveOptions, solve
from rpbench.backends.solve import verify
from rpbench.exceptions import PresetError, SolverError
from rpbench.model import AssignmentModel, PairingModel, Solution, Status, Structure, make_solution


class Fixed(Backend):
    """Answers every model with the columns it was given."""

    name = "fixed"
    requires = ()
    exact = frozenset({Structure.PAIRING})

    def __init__(self, chosen=(), status=Status.OPTIMAL):
        self.chosen, self.status = list(chosen), status

    def solve(self, model, options):
        return make_solution(model, self.chosen, self.status, self.name)


def pairing() -> PairingModel:
    return PairingModel(3, [0, 1], [1, 2], [1.0, 1.0])


def test_verify_rejects_bad_columns():
    model = pairing()
    with pytest.raises(SolverError, match="outside"):
        verify(model, Solution(np.array([5]), 0.0, Status.OPTIMAL, "x"), "x")
    with pytest.raises(SolverError, match="chosen twice"):
        verify(model, Solution(np.array([0, 0]), 0.0, Status.OPTIMAL, "x"), "x")
    with pytest.raises(SolverError, match="covered 2 times"):
        verify(model, Solution(np.array([0, 1]), 0.0, Status.OPTIMAL, "x"), "x")
    with pytest.raises(SolverError, match="boom"):
        verify(model, Solution(np.array([], np.int64), 0.0, Status.ERROR, "x", message="boom"), "x")
    with pytest.raises(SolverError, match="x = 0 is feasible"):
        verify(model, Solution(np.array([], np.int64), 0.0, Status.INFEASIBLE, "x"), "x")
    verify(model, make_solution(model, [1], Status.OPTIMAL, "x"), "x")


def test_an_infeasible_assignment_is_an_honest_answer():
    model = AssignmentModel(1, 1, [0], [0], [1.0])  # no wait option, one vehicle
    verify(model, Solution(np.array([], np.int64), 0.0, Status.INFEASIBLE, "x"), "x")


def test_solve_checks_support_and_verifies_the_answer():
    model = pairing()
    assert solve(model, Preset.of(Fixed([1]))).chosen.tolist() == [1]
    with pytest.raises(SolverError, match="infeasible solution"):
        solve(model, Preset.of(Fixed([0, 1])))
    assignment = AssignmentModel(1, 1, [0, 0], [0, -1], [1.0, 0.0])
    with pytest.raises(PresetError, match="does not solve assignment models"):
        solve(assignment, Preset.of(Fixed()))
    empty = PairingModel(2, [], [], [])
    assert solve(empty, Preset.of(Fixed([7]))).status is Status.OPTIMAL  # nothing to decide: not asked


def test_preset_of_a_backend_object_keeps_options():
    preset = Preset.of(Fixed(), SolveOptions(time_limit_s=3.0))
    assert preset.adapter().name == "fixed" and preset.options.time_limit_s == 3.0
