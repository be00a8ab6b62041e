"""A dense exact backend for the assignment: ``scipy.optimize.linear_sum_assignment``.

The assignment model (rpbench.model.AssignmentModel: passengers x (vehicles
+ keep waiting)) becomes one dense cost matrix, passengers x (vehicles + one
wait slot per passenger): cell (p, v) costs minus the value of column
(p, v), cell (p, V + p) minus the value of p's wait column, every other cell
is forbidden (infinite).  A minimum-cost assignment of every passenger row
is an optimum of the model; when none exists (a passenger without a wait
column and no free vehicle) the model is infeasible.  Values are whole
model units (mm), so the float arithmetic is exact.

Dense means P x (V + P) cells: fine for batch rounds of a few hundred
passengers; larger rounds are refused with a SolverError rather than
swapping the machine to a halt.
"""

from __future__ import annotations

import time

import numpy as np

from rpbench.backends.base import Backend, SolveOptions
from rpbench.exceptions import PresetError, SolverError
from rpbench.model import Model, Solution, Status, Structure, make_solution

#: Largest cost matrix (cells) solved; 2.5e7 float64 cells are 200 MB.
MAX_CELLS = 25_000_000
#: linear_sum_assignment's outcomes -> statuses (it has no time limit and always proves its optimum).
STATUS = {"assigned": Status.OPTIMAL, "cost matrix is infeasible": Status.INFEASIBLE}


class DenseLSABackend(Backend):
    name = "dense-lsa"
    requires = ("scipy",)
    exact = frozenset({Structure.ASSIGNMENT})
    description = "dense scipy.optimize.linear_sum_assignment for the assignment (example plug-in)"

    def solve(self, model: Model, options: SolveOptions) -> Solution:
        _refuse_unsupported(options)
        if model.structure is not Structure.ASSIGNMENT:  # rpbench.backends.solve checks this first
            raise SolverError(f"backend {self.name!r} solves assignment models only, not {model.structure.value}")
        # the solver library loads only when solving: `import rpbench_greedy.backend` stays cheap
        from scipy.optimize import linear_sum_assignment

        t0 = time.perf_counter()
        P, V = model.n_passengers, model.n_vehicles
        if P * (V + P) > MAX_CELLS:
            raise SolverError(
                f"backend {self.name!r}: round {model.name!r} needs a {P} x {V + P} dense matrix, "
                f"more than {MAX_CELLS:,} cells; use a sparse preset (matching, scipy, highs)"
            )
        slot = np.where(model.col_vehicle >= 0, model.col_vehicle, V + model.col_passenger)
        cost = np.full((P, V + P), np.inf)
        cost[model.col_passenger, slot] = -model.values
        column = np.full((P, V + P), -1, dtype=np.int64)
        column[model.col_passenger, slot] = np.arange(model.n_cols)
        t1 = time.perf_counter()
        try:
            rows, cols = linear_sum_assignment(cost)
            outcome = "assigned"
        except ValueError as exc:
            outcome = str(exc)
        t2 = time.perf_counter()
        status = STATUS.get(outcome)
        if status is None:
            raise SolverError(f"backend {self.name!r}: linear_sum_assignment failed on {model.name!r}: {outcome}")
        times = {"build_s": t1 - t0, "solve_s": t2 - t1}
        if status is Status.INFEASIBLE:
            return make_solution(
                model, np.zeros(0, np.int64), status, self.name, message="no assignment serves every passenger", **times
            )
        chosen = column[rows, cols]
        objective = model.objective_of(chosen)
        return make_solution(
            model, chosen, status, self.name, bound=objective, gap=0.0, extract_s=time.perf_counter() - t2, **times
        )


def _refuse_unsupported(options: SolveOptions) -> None:
    """Options this solver cannot honour are an error, never silently ignored."""
    unsupported = {
        "threads": options.threads not in (None, 1),
        "time_limit_s": options.time_limit_s is not None,
        "method": options.method is not None,
        "solver": options.solver is not None,
        "extra": bool(options.extra),
    }
    given = [key for key, bad in unsupported.items() if bad]
    if given:
        raise PresetError(
            f"backend 'dense-lsa' cannot honour option(s) {', '.join(given)} (linear_sum_assignment "
            "is single-threaded, has no time limit and no variants); remove them from the preset"
        )
