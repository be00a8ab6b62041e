"""The one entry point: support checked, the answer verified once (feasible, or honestly infeasible)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rpbench.backends import Backend, Preset, SolveOptions, solve
from rpbench.backends.solve import verify
from rpbench.exceptions import ModelError, PresetError, SolverError
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


@pytest.mark.parametrize(
    "answer, message",
    [
        (None, "returned None on 'pairing', not a rpbench.model.Solution"),
        (Solution(np.array([1]), 1.0, "optimal", "x"), "returned status 'optimal'"),  # type: ignore[arg-type]
        (Solution(np.array([1.5]), 1.0, Status.OPTIMAL, "x"), "fractional chosen column index 1.5"),
        (Solution(np.array([False, True]), 1.0, Status.OPTIMAL, "x"), "np.flatnonzero"),
        (Solution(np.array([0, 1, 0]), 1.0, Status.OPTIMAL, "x"), "3 chosen columns for the 2 columns"),
        (Solution(np.array([1]), 2.0, Status.OPTIMAL, "x"), "reports objective 2.0 on 'pairing', but its chosen"),
        (Solution(np.array([1]), float("nan"), Status.OPTIMAL, "x"), "reports objective nan"),
        (Solution(np.array([1]), 1.0, Status.OPTIMAL, "x", bound=float("inf")), "reports bound inf"),
        (Solution(np.array([1]), 1.0, Status.OPTIMAL, "x", solve_s=-1.0), "solve_s = -1.0"),
    ],
)
def test_verify_refuses_answers_that_are_not_valid_solutions(answer, message):
    with pytest.raises(SolverError, match=re.escape(message)):
        verify(pairing(), answer, "backend 'x'")


def test_verify_normalises_chosen_and_accepts_a_float_echo_of_the_objective():
    model = AssignmentModel(2, 2, [0, 1, 0, 1], [0, 1, -1, -1], [3.0, 4.0, 0.0, 0.0])
    got = verify(model, Solution([1, 0], 7.0 + 1e-12, Status.OPTIMAL, "x"), "x")  # type: ignore[arg-type]
    assert got.chosen.tolist() == [0, 1] and got.chosen.dtype == np.int64 and not got.chosen.flags.writeable
    answer = make_solution(model, [0, 1], Status.OPTIMAL, "x")
    assert verify(model, answer, "x") is answer  # already canonical: not copied


@pytest.mark.parametrize(
    "chosen, message",
    [([0.5], "chose column index 0.5"), ([1, 1], "chose a column of 'pairing' twice"), ([[1]], "shape (1, 1)")],
)
def test_make_solution_never_casts_or_deduplicates_into_another_answer(chosen, message):
    with pytest.raises(SolverError, match=re.escape(message)):
        make_solution(pairing(), chosen, Status.OPTIMAL, "x")


def test_a_model_changed_to_nan_after_construction_never_reaches_the_backend():
    model = pairing()
    model.values[0] = np.nan
    backend = Fixed([1])
    backend.solve = lambda model, options: pytest.fail("the backend was asked")  # type: ignore[method-assign]
    with pytest.raises(ModelError, match="value of column 0 is nan"):
        solve(model, Preset.of(backend))
