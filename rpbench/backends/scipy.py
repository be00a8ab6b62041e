"""SciPy: sparse bipartite matching for the assignment, ``scipy.optimize.milp`` (HiGHS) otherwise.

The assignment is a minimum-weight *full* matching of the passengers in the
biadjacency matrix passengers x (vehicles + one wait slot per passenger),
solved by ``scipy.sparse.csgraph.min_weight_full_bipartite_matching``
(LAPJVsp; exact for integral costs, no time limit).  Costs are shifted per
passenger to be >= 1 (every passenger is matched once, so the argmin is
unchanged; csgraph treats zeros as missing edges).  Trip packing and pairing
go to ``milp`` (HiGHS inside SciPy; no thread option, no warm start).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw, raw_state
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.base import SolveOptions
from rpbench.model import AssignmentModel, Solution, Status, make_solution

#: scipy.optimize.milp status -> raw state (0 optimal, 1 iteration/time limit, 2 infeasible).
STATUS = {0: OPTIMAL, 1: LIMIT, 2: INFEASIBLE}


class ScipyBackend(ProgramBackend):
    name = "scipy"
    requires = ("scipy",)
    description = "SciPy: min_weight_full_bipartite_matching for the assignment, scipy.optimize.milp (HiGHS) otherwise"

    def solve_assignment(self, model: AssignmentModel, options: SolveOptions, clock: Clock) -> Solution:
        if options.method == "mip":
            return super().solve_assignment(model, options, clock)
        from scipy.sparse.csgraph import min_weight_full_bipartite_matching

        with clock("build_s"):
            P, V = model.n_passengers, model.n_vehicles
            cp, cv, val = model.col_passenger, model.col_vehicle, model.values
            top = np.full(P, -np.inf)
            np.maximum.at(top, cp, val)
            cost = top[cp] - val + 1.0
            slot = np.where(cv >= 0, cv, V + cp).astype(np.int64)
            g = sp.csr_matrix((cost, (cp, slot)), shape=(P, V + P))
            key = cp.astype(np.int64) * (V + P) + slot
            order = np.argsort(key)
        with clock("solve_s"):
            try:
                rows, match = min_weight_full_bipartite_matching(g)
            except ValueError:  # no full matching: some passenger cannot be served
                return make_solution(
                    model,
                    np.zeros(0, np.int64),
                    Status.INFEASIBLE,
                    self.name,
                    message="no assignment serves every passenger without a wait option",
                    **clock.times,
                )
        with clock("extract_s"):
            chosen = order[np.searchsorted(key[order], rows.astype(np.int64) * (V + P) + match)]
            chosen = np.sort(chosen)
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
        from scipy.optimize import Bounds, LinearConstraint, milp

        with clock("build_s"):
            opts = {"disp": False, "mip_rel_gap": float(options.mip_rel_gap), **options.extra}
            if time_limit is not None:
                opts["time_limit"] = max(float(time_limit), 1e-3)
            constraint = LinearConstraint(prog.A, prog.lo, prog.hi)
            integrality = np.zeros(prog.n) if relax else np.ones(prog.n)
        with clock("solve_s"):
            res = milp(-prog.c, integrality=integrality, bounds=Bounds(0.0, 1.0), constraints=constraint, options=opts)
        with clock("extract_s"):
            state = raw_state(STATUS, res.status, f"scipy.optimize.milp ({res.message})")
            bound = getattr(res, "mip_dual_bound", None)
            bound = None if bound is None or relax else -float(bound)
            if relax and state == OPTIMAL:
                bound = -float(res.fun)
            x = None if res.x is None else np.asarray(res.x, dtype=np.float64)
        return Raw(x=x, state=state, bound=bound, message="" if state == OPTIMAL else str(res.message))
