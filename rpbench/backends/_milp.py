"""Backends that solve the generic 0/1 program of a model (HiGHS, SciPy, Pyomo, CVXPY, CP-SAT).

A subclass implements :meth:`ProgramBackend.run` — one solve of a
:class:`~rpbench.backends._common.Program` — and inherits:

* the assignment as an LP (``method = "lp"``, the default): its constraint
  matrix is the incidence matrix of a bipartite graph, totally unimodular,
  so a simplex vertex is integral (paper Eqs. 1-4); the answer is checked
  and, should it be fractional, re-solved as a MIP;
* Oracle-2 (``objective = "cardinality_then_weight"``, docs/algorithms.md §4.3) in
  two exact stages: stage 1 finds the largest number of pairs ``k*`` by
  Edmonds' algorithm (combinatorial, certified by a Tutte-Berge set); stage 2
  is the solver's MIP maximising the value subject to ``Σ x >= k*``,
  warm-started where the solver accepts a hint.  The time limit covers both.
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from rpbench.backends._common import LIMIT, OPTIMAL, Clock, Program, Raw, finish, program
from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.cardinality import columns_of_mate, maximum_cardinality_matching
from rpbench.exceptions import SolverError
from rpbench.model import AssignmentModel, Model, PairingModel, Solution, Structure, empty_solution

ALL = frozenset(Structure)


class ProgramBackend(Backend):
    exact = ALL
    accepts_hint = True
    #: Backends whose ``run`` can solve the LP relaxation.
    can_relax = True

    @abstractmethod
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
        """Solve ``prog`` once (``relax``: x in [0, 1]); times go to ``clock``."""

    def solve(self, model: Model, options: SolveOptions, hint: np.ndarray | None = None) -> Solution:
        """Solve ``model``; ``hint`` (0/1 per column, feasible) warm-starts packing and pairing MIPs."""
        self.ensure_installed()
        if model.n_cols == 0:
            return empty_solution(model, self.name)
        clock = Clock()
        if isinstance(model, AssignmentModel):
            return self.solve_assignment(model, options, clock)
        if isinstance(model, PairingModel) and model.objective == "cardinality_then_weight":
            return self.solve_lexicographic(model, options, clock, hint)
        raw = self.run(program(model), options, clock, time_limit=options.time_limit_s, hint=hint)
        if raw.x is None and hint is not None and raw.state == LIMIT:
            raw.x = np.round(hint)  # stopped before adopting the (feasible) warm start
        return finish(model, raw, self.name, clock, options.mip_rel_gap)

    def solve_assignment(self, model: AssignmentModel, options: SolveOptions, clock: Clock) -> Solution:
        method = options.method or ("lp" if self.can_relax else "mip")
        if method not in ("lp", "mip"):
            raise SolverError(f"backend {self.name!r}: method {method!r} unknown for the assignment; use lp or mip")
        prog = program(model)
        if method == "lp":
            try:
                raw = self.run(prog, options, clock, relax=True, time_limit=options.time_limit_s)
            except SolverError as exc:
                # seen on a full-day FL-nd round: HiGHS's presolved simplex ends "kUnknown" when wait
                # values (-1e9) dwarf the rest; the MIP (same solver) proves the optimum
                note = f"LP failed ({exc}); re-solved as a MIP"
                raw = self.run(prog, options, clock, time_limit=clock.remaining(options.time_limit_s))
                return finish(model, raw, self.name, clock, options.mip_rel_gap, message=note)
            x = raw.x
            if raw.state != OPTIMAL or x is None:
                return finish(model, raw, self.name, clock, options.mip_rel_gap)
            integral, chosen = _integral_support(x)
            if integral:  # the columns set to 1, read once: finish() need not check the same values again
                return finish(model, raw, self.name, clock, options.mip_rel_gap, chosen=chosen)
            note = "LP vertex was fractional (numerical trouble); re-solved as a MIP"
            raw = self.run(prog, options, clock, time_limit=clock.remaining(options.time_limit_s))
            return finish(model, raw, self.name, clock, options.mip_rel_gap, message=note)
        raw = self.run(prog, options, clock, time_limit=options.time_limit_s)
        return finish(model, raw, self.name, clock, options.mip_rel_gap)

    def solve_lexicographic(
        self, model: PairingModel, options: SolveOptions, clock: Clock, hint: np.ndarray | None = None
    ) -> Solution:
        """Oracle-2: ``k*`` exactly by Edmonds' algorithm (certified, :mod:`.cardinality`), then the MIP.

        A MIP for the cardinality stage is massively degenerate (every
        matching of a size ties) and crawls at scale; the combinatorial
        algorithm takes under a second on the full day.  The MIP maximises the
        value subject to ``Σ x >= k*``, warm-started from the caller's hint if
        it has ``k*`` pairs, else from Edmonds' matching.
        """
        with clock("build_s"):
            n, a, b = model.n_orders, model.col_a.astype(np.int64), model.col_b.astype(np.int64)
            top = maximum_cardinality_matching(n, a, b)
            k = top.size
            start = np.zeros(model.n_cols)
            start[columns_of_mate(n, a, b, top.mate)] = 1.0
            if hint is not None and np.round(hint).sum() >= k:
                start = np.round(hint)  # the caller's start has k* pairs and, likely, more weight
        remaining = clock.remaining(options.time_limit_s)
        if remaining is not None and remaining <= 0:
            return finish(model, Raw(x=start, state=LIMIT, message="time limit after stage 1"), self.name, clock)
        stage2 = self.run(program(model, min_count=k), options, clock, time_limit=remaining, hint=start)
        if stage2.x is None:
            stage2.x = start  # a maximum-cardinality matching is feasible for stage 2
        return finish(model, stage2, self.name, clock, options.mip_rel_gap)


def _integral_support(x) -> tuple[bool, np.ndarray | None]:
    """Whether every LP value lies within 1e-6 of an integer (a NaN is not) and, for one-dimensional
    values, the columns set to 1 (as :func:`~rpbench.backends._common.chosen_columns` reads them)."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        return bool(np.abs(x - np.round(x)).max(initial=0.0) <= 1e-6), None
    from rpbench.model import kernels  # compiled on first use

    worst, _, chosen = kernels.integral_support(x)
    return worst <= 1e-6, chosen
