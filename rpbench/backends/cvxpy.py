"""CVXPY: boolean variables and sparse constraint matrices, solved by ``options.solver`` (default HiGHS).

``build_s`` covers building the CVXPY problem and compiling it for the
solver (``Problem.get_problem_data``); ``solve_s`` is the solver call alone
(``solve_via_data``).  The assignment is an LP (``method = "lp"``, the
default: integral, checked), the rest MIPs.  Options reach HiGHS as
:func:`rpbench.backends.highs.highs_settings` gives them; for other solvers
only ``[options.extra]`` is passed, verbatim.
"""

from __future__ import annotations

import warnings

import numpy as np

from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw, raw_state
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.base import SolveOptions
from rpbench.backends.highs import highs_settings
from rpbench.exceptions import SolverError, SolverNotInstalledError

#: CVXPY problem status -> raw state (CVXPY's status names are plain strings).
STATUS = {
    "optimal": OPTIMAL,
    "infeasible": INFEASIBLE,
    "infeasible_inaccurate": INFEASIBLE,
    "user_limit": LIMIT,
    "optimal_inaccurate": LIMIT,
}


class CvxpyBackend(ProgramBackend):
    name = "cvxpy"
    requires = ("cvxpy", "highspy")
    description = "A CVXPY problem with boolean variables and sparse constraints, solved by HiGHS"

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
        import cvxpy as cp

        solver = (options.solver or "HIGHS").upper()
        if solver not in cp.installed_solvers():
            raise SolverNotInstalledError(
                f"CVXPY solver {solver!r} is not installed; installed: {', '.join(cp.installed_solvers())}"
            )
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
            opts = highs_settings(options, time_limit, relax=relax) if solver == "HIGHS" else dict(options.extra)
        with clock("solve_s"):
            try:
                result = chain.solve_via_data(problem, data, warm_start=False, verbose=False, solver_opts=opts)
            except cp.error.SolverError as exc:
                raise SolverError(f"CVXPY solver {solver} failed: {exc}") from None
        with clock("extract_s"):
            with warnings.catch_warnings():  # "may be inaccurate" on a time limit: the status says so
                warnings.simplefilter("ignore", UserWarning)
                try:
                    problem.unpack_results(result, chain, inverse)
                except ValueError as exc:  # CVXPY refuses a solution without a status
                    raise SolverError(f"CVXPY solver {solver} returned no usable solution: {exc}") from None
            status = problem.status
            state = raw_state(STATUS, status, f"CVXPY solver {solver}")
            if state == INFEASIBLE:
                return Raw(x=None, state=INFEASIBLE)
            xs = None if x.value is None else np.asarray(x.value, dtype=np.float64)
            bound = None
            info = problem.solver_stats.extra_stats if problem.solver_stats else None
            if relax:
                bound = float(problem.value) if state == OPTIMAL else None
            elif info is not None and hasattr(info, "mip_dual_bound"):
                bound = -float(info.mip_dual_bound)  # CVXPY hands HiGHS "minimise -c·x"
        return Raw(x=xs, state=state, bound=bound, message="" if state == OPTIMAL else f"CVXPY status {status}")
