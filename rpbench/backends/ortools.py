"""OR-Tools: min-cost flow for the assignment, CP-SAT for trip packing and pairing.

The assignment is a min-cost flow (``SimpleMinCostFlow``, integer costs —
model values are integral): one unit of supply per passenger, arcs
passenger -> vehicle and passenger -> sink (wait), vehicle -> sink of
capacity 1.  It is exact and polynomial; it has no time limit.

Trip packing and pairing go to CP-SAT with integer objective coefficients,
``num_workers = threads`` (default 1) and ``random_seed = 0`` so identical
input gives identical output; ``method = "cp"`` sends the assignment to
CP-SAT as well.
"""

from __future__ import annotations

import numpy as np

from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw, raw_state
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.base import SolveOptions
from rpbench.exceptions import SolverError
from rpbench.model import AssignmentModel, Solution, Status, make_solution

#: CP-SAT status name -> raw state (UNKNOWN: stopped by a limit, perhaps without a solution).
CP_SAT_STATUS = {"OPTIMAL": OPTIMAL, "FEASIBLE": LIMIT, "UNKNOWN": LIMIT, "INFEASIBLE": INFEASIBLE}


class OrtoolsBackend(ProgramBackend):
    name = "ortools"
    requires = ("ortools",)
    description = "OR-Tools: min-cost flow for the assignment, CP-SAT for trip packing and pairing"
    can_relax = False

    def solve_assignment(self, model: AssignmentModel, options: SolveOptions, clock: Clock) -> Solution:
        if options.method in ("cp", "mip"):
            return super().solve_assignment(model, SolveOptions(**{**options.__dict__, "method": "mip"}), clock)
        if options.method not in (None, "flow"):
            raise SolverError(
                f"backend {self.name!r}: method {options.method!r} unknown for the assignment; use flow or cp"
            )
        from ortools.graph.python import min_cost_flow

        with clock("build_s"):
            P, V = model.n_passengers, model.n_vehicles
            cp, cv = model.col_passenger.astype(np.int64), model.col_vehicle.astype(np.int64)
            ride = cv >= 0
            sink = P + V
            col_of_arc = np.concatenate([np.flatnonzero(ride), np.flatnonzero(~ride)])
            tails = np.concatenate([cp[col_of_arc], P + np.arange(V)])
            heads = np.concatenate([P + cv[ride], np.full(int((~ride).sum()), sink), np.full(V, sink)])
            costs = np.concatenate([-model.values[col_of_arc], np.zeros(V)]).astype(np.int64)
            flow = min_cost_flow.SimpleMinCostFlow()
            arcs = flow.add_arcs_with_capacity_and_unit_cost(tails, heads, np.ones(len(tails), np.int64), costs)
            supplies = np.concatenate([np.ones(P, np.int64), np.zeros(V, np.int64), [-P]])
            flow.set_nodes_supplies(np.arange(P + V + 1), supplies)
        with clock("solve_s"):
            status = flow.solve()
        with clock("extract_s"):
            if status in (flow.INFEASIBLE, flow.UNBALANCED):
                return make_solution(
                    model,
                    np.zeros(0, np.int64),
                    Status.INFEASIBLE,
                    self.name,
                    message="no assignment serves every passenger without a wait option",
                    **clock.times,
                )
            if status != flow.OPTIMAL:
                raise SolverError(
                    f"OR-Tools min-cost flow failed with status {status!r} "
                    "(BAD_COST_RANGE: values too large for int64 path costs)"
                )
            used = np.asarray(flow.flows(arcs[: model.n_cols])) > 0
            chosen = np.sort(col_of_arc[used])
        obj = model.objective_of(chosen)
        return make_solution(model, chosen, Status.OPTIMAL, self.name, bound=obj, gap=0.0, **clock.times)

    def run(
        self,
        prog: Program,
        options: SolveOptions,
        clock: Clock,
        *,
        relax: bool = False,
        time_limit: float | None = None,
        hint: np.ndarray | None = None,
    ) -> Raw:
        from ortools.sat.python import cp_model

        with clock("build_s"):
            coeffs = prog.c.astype(np.int64)
            if not np.array_equal(coeffs, prog.c):
                raise SolverError("CP-SAT needs integral objective coefficients")
            model = cp_model.CpModel()
            x = [model.new_bool_var("") for _ in range(prog.n)]
            A = prog.A.tocsr()
            starts, cols = A.indptr, A.indices
            for r in range(A.shape[0]):
                members = [x[j] for j in cols[starts[r] : starts[r + 1]]]
                lo, hi = prog.lo[r], prog.hi[r]
                if lo == 1 and hi == 1:
                    model.add_exactly_one(members)
                elif hi == 1 and not np.isfinite(lo):
                    model.add_at_most_one(members)
                else:  # the cardinality row Σx >= k of Oracle-2's second stage
                    model.add(cp_model.LinearExpr.sum(members) >= int(lo))
            model.maximize(cp_model.LinearExpr.weighted_sum(x, coeffs.tolist()))
            if hint is not None:
                for var, value in zip(x, np.round(hint).astype(int).tolist(), strict=True):
                    model.add_hint(var, value)
            solver = cp_model.CpSolver()
            params = solver.parameters
            params.num_workers = int(options.threads or 1)
            params.random_seed = 0
            params.relative_gap_limit = float(options.mip_rel_gap)
            if time_limit is not None:
                params.max_time_in_seconds = max(float(time_limit), 1e-3)
            for key, value in options.extra.items():
                setattr(params, key, value)
        with clock("solve_s"):
            status = solver.solve(model)
        with clock("extract_s"):
            state = raw_state(CP_SAT_STATUS, solver.status_name(status), "CP-SAT")
            if state == INFEASIBLE:
                return Raw(x=None, state=INFEASIBLE)
            has_x = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
            xs = np.asarray(solver.response_proto.solution, dtype=np.float64)[: prog.n] if has_x else None
            bound = float(solver.best_objective_bound) if has_x else None  # without a solution it may be 0
        return Raw(
            x=xs,
            state=state,
            bound=bound,
            message="" if state == OPTIMAL else f"CP-SAT status {solver.status_name(status)}",
        )
