"""CVXPY: boolean variables and sparse constraint matrices, solved by ``options.solver`` (default HiGHS).

``build_s`` covers building the CVXPY problem and compiling it for the
solver (``Problem.get_problem_data``); ``solve_s`` is the solver call alone
(``solve_via_data``).  The assignment is an LP (``method = "lp"``, the
default: integral, checked), the rest MIPs.  Options reach HiGHS by name
(``time_limit``, ``mip_rel_gap``, ``threads``, ``random_seed``); for other
solvers only ``[options.extra]`` is passed, verbatim.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..exceptions import SolverError, SolverNotInstalledError
from .base import SolveOptions
from ._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw
from ._milp import ProgramBackend


class CvxpyBackend(ProgramBackend):
    name = "cvxpy"
    requires = ("cvxpy", "highspy")
    description = "A CVXPY problem with boolean variables and sparse constraints, solved by HiGHS"

    def run(self, prog: Program, options: SolveOptions, clock: Clock, *, relax: bool = False,
            time_limit: float | None = None, hint: np.ndarray | None = None) -> Raw:
        import cvxpy as cp

        solver = (options.solver or "HIGHS").upper()
        if solver not in cp.installed_solvers():
            raise SolverNotInstalledError(f"CVXPY solver {solver!r} is not installed; installed: "
                                          f"{', '.join(cp.installed_solvers())}")
        with clock("build_s"):
            x = cp.Variable(prog.n, bounds=[0, 1]) if relax else cp.Variable(prog.n, boolean=True)
            eq = prog.lo == prog.hi
            le = ~eq & np.isinf(prog.lo)
            ge = ~eq & ~le
            A = prog.A.tocsr()
            constraints = [A[rows] @ x == prog.hi[rows] for rows in [np.flatnonzero(eq)] if len(rows)]
            constraints += [A[rows] @ x <= prog.hi[rows] for rows in [np.flatnonzero(le)] if len(rows)]
            constraints += [A[rows] @ x >= prog.lo[rows] for rows in [np.flatnonzero(ge)] if len(rows)]
            problem = cp.Problem(cp.Maximize(prog.c @ x), constraints)
            data, chain, inverse = problem.get_problem_data(solver=solver)
            opts = dict(options.extra)
            if solver == "HIGHS":
                opts.update({"mip_rel_gap": float(options.mip_rel_gap), "random_seed": 0})
                if options.threads is not None:
                    opts["threads"] = int(options.threads)
                if time_limit is not None:
                    opts["time_limit"] = max(float(time_limit), 1e-3)
                if relax:
                    opts["solver"] = "simplex"      # a vertex, hence integral for the assignment
                    opts.setdefault("presolve", "off")   # 10-20x faster, see backends/highs.py
        with clock("solve_s"):
            try:
                result = chain.solve_via_data(problem, data, warm_start=False, verbose=False, solver_opts=opts)
            except cp.error.SolverError as exc:
                raise SolverError(f"CVXPY solver {solver} failed: {exc}") from None
        with clock("extract_s"):
            with warnings.catch_warnings():           # "may be inaccurate" on a time limit: the status says so
                warnings.simplefilter("ignore", UserWarning)
                try:
                    problem.unpack_results(result, chain, inverse)
                except ValueError as exc:            # CVXPY refuses a solution without a status
                    raise SolverError(f"CVXPY solver {solver} returned no usable solution: {exc}") from None
            status = problem.status
            if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
                return Raw(x=None, state=INFEASIBLE)
            if status == cp.OPTIMAL:
                state = OPTIMAL
            elif status in (cp.USER_LIMIT, cp.OPTIMAL_INACCURATE):
                state = LIMIT
            else:
                raise SolverError(f"CVXPY solver {solver} ended with status {status!r}")
            xs = None if x.value is None else np.asarray(x.value, dtype=np.float64)
            bound = None
            info = problem.solver_stats.extra_stats if problem.solver_stats else None
            if relax:
                bound = float(problem.value) if state == OPTIMAL else None
            elif info is not None and hasattr(info, "mip_dual_bound"):
                bound = -float(info.mip_dual_bound)      # CVXPY hands HiGHS "minimise -c·x"
        return Raw(x=xs, state=state, bound=bound, message="" if state == OPTIMAL else f"CVXPY status {status}")
