"""The one way to solve a model: :func:`solve` (used by the simulator, the oracle and the benchmark).

It checks that the preset's backend is installed and solves the model's
structure exactly, solves, and verifies the answer once — every chosen
column inside the model, no row over-covered, every "exactly once" row
covered — so no caller has to repeat the check, and an adapter that answers
wrongly is an error naming it, never a silently wrong result.
"""

from __future__ import annotations

import numpy as np

from rpbench.backends.presets import Preset
from rpbench.exceptions import SolverError
from rpbench.model import Model, Solution, Status, Structure, empty_solution


def solve(model: Model, preset: Preset, *, hint: np.ndarray | None = None) -> Solution:
    """Solve ``model`` with ``preset``; ``hint`` (0/1 per column, feasible) warm-starts backends that take one."""
    backend = preset.require(model.structure)
    if model.n_cols == 0:
        return empty_solution(model, backend.name)
    if hint is not None and backend.accepts_hint:
        solution = backend.solve(model, preset.options, hint=hint)  # type: ignore[call-arg]
    else:
        solution = backend.solve(model, preset.options)
    verify(model, solution, preset.name)
    return solution


def verify(model: Model, solution: Solution, solver: str) -> None:
    """Raise :class:`SolverError` unless ``solution`` is a feasible answer (or an honest infeasible one)."""
    if solution.status is Status.ERROR:
        raise SolverError(f"solver {solver!r} failed on {model.name!r}: {solution.message or 'no message'}")
    if solution.status is Status.INFEASIBLE:
        if model.structure is not Structure.ASSIGNMENT:  # x = 0 is feasible for packing and pairing
            raise SolverError(f"solver {solver!r} reports {model.name!r} infeasible, but x = 0 is feasible")
        return
    problems = model.violations(solution.chosen)
    if problems:
        raise SolverError(f"solver {solver!r} returned an infeasible solution of {model.name!r}: {problems[0]}")
