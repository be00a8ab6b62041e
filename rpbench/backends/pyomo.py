"""Pyomo: an algebraic model (one binary variable per column, one constraint per row).

Solved by HiGHS through Pyomo's persistent appsi interface (``options.solver
= "appsi_highs"``, the default): ``build_s`` covers building the Pyomo model
and translating it into HiGHS (``set_instance``), ``solve_s`` the HiGHS run.
Any other solver Pyomo's ``SolverFactory`` knows (``highs``, ``cbc``,
``glpk``, ``gurobi`` ... if installed) is called through the legacy
interface with ``timelimit`` and ``[options.extra]`` as its options; its
translation then counts as solve time.  The assignment is an LP (integral,
checked), the rest MIPs.
"""

from __future__ import annotations

import logging

import numpy as np

from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw, raw_state
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.base import SolveOptions
from rpbench.backends.highs import highs_settings
from rpbench.exceptions import SolverNotInstalledError

#: Pyomo termination condition name -> raw state (appsi and legacy interfaces).
STATUS = {
    "optimal": OPTIMAL,
    **{name: INFEASIBLE for name in ("infeasible", "infeasibleOrUnbounded", "invalidProblem")},
    **{
        name: LIMIT
        for name in (
            "maxTimeLimit",
            "maxIterations",
            "objectiveLimit",
            "interrupted",
            "maxEvaluations",
            "minStepLength",
            "iterationLimit",
            "userInterrupt",
            "other",
        )
    },
}


def _state(condition, solver: str) -> str:
    return raw_state(STATUS, getattr(condition, "name", str(condition)), solver)


def pyomo_model(prog: Program, relax: bool):
    """The Pyomo model of a 0/1 program (``x[j]``, ``row[r]``, ``objective``)."""
    import pyomo.environ as pyo

    m = pyo.ConcreteModel()
    m.x = pyo.Var(range(prog.n), domain=pyo.UnitInterval if relax else pyo.Binary)
    A = prog.A.tocsr()
    starts, cols = A.indptr, A.indices
    x = [m.x[j] for j in range(prog.n)]

    def row(m, r):
        lo, hi = prog.lo[r], prog.hi[r]
        if starts[r] == starts[r + 1]:
            return pyo.Constraint.Skip  # an idle vehicle or request: nothing covers it
        body = pyo.quicksum(x[j] for j in cols[starts[r] : starts[r + 1]])
        return (float(lo) if np.isfinite(lo) else None, body, float(hi) if np.isfinite(hi) else None)

    m.row = pyo.Constraint(range(A.shape[0]), rule=row)
    m.objective = pyo.Objective(
        expr=pyo.quicksum(float(c) * xj for c, xj in zip(prog.c, x, strict=True) if c != 0), sense=pyo.maximize
    )
    return m, x


class PyomoBackend(ProgramBackend):
    name = "pyomo"
    requires = ("pyomo", "highspy")
    description = "A Pyomo model solved by HiGHS through Pyomo's appsi interface (or another installed solver)"

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
        solver = options.solver or "appsi_highs"
        if solver == "appsi_highs":
            return self._run_appsi(prog, options, clock, relax, time_limit, hint)
        return self._run_legacy(solver, prog, options, clock, relax, time_limit)

    def _run_appsi(self, prog, options, clock, relax, time_limit, hint) -> Raw:
        from pyomo.contrib.appsi.solvers import Highs

        with clock("build_s"):
            m, x = pyomo_model(prog, relax)
            opt = Highs()
            opt.config.load_solution = False
            settings = highs_settings(options, time_limit, relax=relax)
            opt.config.time_limit = settings.pop("time_limit", None)  # appsi passes these two itself
            opt.config.mip_gap = settings.pop("mip_rel_gap")
            opt.highs_options = settings
            uc = opt.update_config  # the model is final: skip appsi's change detection in solve()
            for flag in (
                "check_for_new_or_removed_constraints",
                "check_for_new_or_removed_vars",
                "check_for_new_or_removed_params",
                "check_for_new_objective",
                "update_constraints",
                "update_vars",
                "update_params",
                "update_named_expressions",
                "update_objective",
            ):
                setattr(uc, flag, False)
            if hint is not None and not relax:
                for var, value in zip(x, np.round(hint).tolist(), strict=True):
                    var.set_value(value)
                opt.config.warmstart = True
            opt.set_instance(m)
        with clock("solve_s"):
            results = opt.solve(m)
        with clock("extract_s"):
            state = _state(results.termination_condition, "Pyomo/HiGHS")
            xs = None
            if state != INFEASIBLE and results.best_feasible_objective is not None:
                values = results.solution_loader.get_primals(x)
                xs = np.array([values[v] for v in x], dtype=np.float64)
            bound = results.best_objective_bound
        return Raw(
            x=xs,
            state=state,
            bound=None if bound is None else float(bound),
            message="" if state == OPTIMAL else f"Pyomo termination {results.termination_condition}",
        )

    def _run_legacy(self, solver, prog, options, clock, relax, time_limit) -> Raw:
        import pyomo.environ as pyo
        from pyomo.common.log import LoggingIntercept

        opt = pyo.SolverFactory(solver)
        if not opt.available(exception_flag=False):
            raise SolverNotInstalledError(
                f"Pyomo solver {solver!r} is not available; install it or use the default appsi_highs"
            )
        with clock("build_s"):
            m, x = pyomo_model(prog, relax)
        with clock("solve_s"):
            kwargs = {"load_solutions": False, "options": dict(options.extra)}
            if time_limit is not None:
                kwargs["timelimit"] = max(float(time_limit), 1e-3)
            results = opt.solve(m, **kwargs)
        with clock("extract_s"):
            state = _state(results.solver.termination_condition, f"Pyomo solver {solver}")
            xs = None
            if state != INFEASIBLE and len(results.solution) > 0:
                with LoggingIntercept(level=logging.WARNING):  # "loading an 'aborted' result": the status says so
                    m.solutions.load_from(results)
                xs = np.array([v.value if v.value is not None else 0.0 for v in x], dtype=np.float64)
            bound = results.problem.upper_bound
            bound = float(bound) if bound is not None and np.isfinite(float(bound)) else None
        return Raw(
            x=xs,
            state=state,
            bound=bound,
            message="" if state == OPTIMAL else f"Pyomo termination {results.solver.termination_condition}",
        )
