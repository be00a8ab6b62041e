"""HiGHS through highspy, the model passed in bulk as CSC arrays (``Highs.passModel``).

The assignment is solved as an LP by the simplex method (integral by total
unimodularity, checked), trip packing and pairing as MIPs; Oracle-2 in two
stages (see :mod:`rpbench.backends._milp`).  HiGHS is deterministic for a
given thread count (default 1) and ``random_seed`` (fixed to 0).

highspy must be 1.12-1.14: 1.15 ships ``libhighs.so.1``, the soname of the
HiGHS bundled in OR-Tools 9.15, and the two then cannot load in one process.
"""

from __future__ import annotations

import threading
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Program, Raw, raw_state
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.base import SolveOptions
from rpbench.backends.unique import unique_optimum
from rpbench.exceptions import SolverError
from rpbench.model import Model, Solution, Status, Structure, make_solution

if TYPE_CHECKING:
    import highspy

#: HiGHS model status name -> raw state (x in [0, 1]: "unbounded or infeasible" is infeasible).
STATUS = {
    "kOptimal": OPTIMAL,
    "kInfeasible": INFEASIBLE,
    "kUnboundedOrInfeasible": INFEASIBLE,
    **{
        name: LIMIT
        for name in (
            "kTimeLimit",
            "kIterationLimit",
            "kSolutionLimit",
            "kObjectiveBound",
            "kObjectiveTarget",
            "kInterrupt",
            "kHighsInterrupt",
            "kMemoryLimit",
        )
    },
}


def highs_settings(options: SolveOptions, time_limit: float | None, *, relax: bool) -> dict:
    """HiGHS option values for a preset's options: the one place rpbench sets HiGHS options.

    Used by the highs adapter and by the CVXPY and Pyomo adapters when they
    run HiGHS; ``[options.extra]`` comes last and wins.
    """
    settings: dict = {"output_flag": False, "random_seed": 0, "mip_rel_gap": float(options.mip_rel_gap)}
    if options.threads is not None:
        settings["threads"] = int(options.threads)
    if time_limit is not None:
        settings["time_limit"] = max(float(time_limit), 1e-3)
    if relax:
        settings["solver"] = "simplex"  # a vertex, hence integral for the assignment
        # HiGHS 1.14's presolve finds nothing to remove in this LP (0/1 columns, one row per passenger
        # and per vehicle) yet dominates its time: 2,000 x 5,000 (1.27 M columns) 32 s vs 1.6 s without,
        # 100 x 500 45 ms vs 5 ms; the presolved simplex also ended "kUnknown" on a full-day FL-nd round.
        # [options.extra] presolve = "on" restores it.
        settings["presolve"] = "off"
    settings.update(options.extra)
    return settings


def _apply(h: highspy.Highs, settings: dict) -> None:
    for key, value in settings.items():
        if h.setOptionValue(key, value).name == "kError":
            raise SolverError(f"HiGHS rejected option {key} = {value!r}; see the HiGHS option list")


class _Kept(threading.local):
    """This thread's HiGHS instances by role, with the settings their options were last set to (None: unknown)."""

    def __init__(self) -> None:
        self.highs: dict[str, highspy.Highs] = {}
        self.settings: dict[str, dict | None] = {}


_kept = _Kept()


def kept_instance(settings: dict, role: str = "solve", *, lp: bool = False) -> highspy.Highs:
    """This thread's ``highspy.Highs`` for ``role``, its previous model cleared and its options set to ``settings``.

    Constructing a Highs object costs about 0.15 ms, more than solving a typical
    simulation round's LP, so one instance per thread is kept.  ``clearModel``
    drops the previous model with its solution and basis; options are reset to
    HiGHS's defaults before ``settings`` are applied whenever they differ from
    the previous solve's.  A second role (the trip-packing LP of
    :mod:`.unique`) keeps its own instance, so alternating LP and MIP rounds
    do not reset options every time.
    """
    import highspy

    h = _kept.highs.get(role)
    if h is None:
        h = _kept.highs[role] = highspy.Highs()
        for event in (h.cbSimplexInterrupt, h.cbIpmInterrupt, h.cbMipInterrupt):
            event.subscribe(_let_signals_in)
    else:
        h.clearModel()
    if _kept.settings.get(role) != settings:
        h.resetOptions()
        _kept.settings[role] = None  # unknown until every option is accepted
        _apply(h, settings)
        _kept.settings[role] = dict(settings)
    if lp and "time_limit" in settings:
        # HiGHS (before 2.0) compares an LP's time_limit with the instance's run time summed over every run,
        # and clearModel does not reset that clock (ERGO-Code/HiGHS#1331, #1477): a kept instance would stop
        # at once on every LP after its first ``time_limit`` seconds of solving, so the limit is moved on.
        # Its MIP solver measures each run from its start (tested): a MIP's limit stays as it is.
        h.setOptionValue("time_limit", h.getRunTime() + float(settings["time_limit"]))
    return h


def _let_signals_in(event) -> None:
    """HiGHS's periodic interrupt check, made a moment of Python in the solving thread.

    ``Highs.run()`` is one C++ call: a Python signal handler (the CLI turns SIGTERM into an
    exception, Ctrl-C is KeyboardInterrupt) cannot run until it returns, so a long solve ignored
    both.  Subscribing this no-op callback makes HiGHS call into Python at its interrupt checks;
    a pending handler runs there and its exception leaves ``run()`` (:func:`run_interruptibly`).
    """


def run_interruptibly(h: highspy.Highs, solve=None):
    """``h.run()`` (or ``solve()`` on ``h``) where a signal handler's exception may end it; ``h`` is then
    dropped from this thread's kept instances (the exception crossed HiGHS: its state is not trusted)."""
    try:
        return h.run() if solve is None else solve()
    except BaseException:
        for role, kept in list(_kept.highs.items()):
            if kept is h:
                del _kept.highs[role]
                _kept.settings.pop(role, None)
        raise


class HighsBackend(ProgramBackend):
    name = "highs"
    requires = ("highspy",)
    description = "HiGHS via highspy (bulk CSC arrays): simplex LP for the assignment, MIP for packing and pairing"

    def load(self) -> None:
        """Import highspy (when installed; a missing one is reported by the solve)."""
        if self.is_installed():
            import highspy  # noqa: F401

    def solve(self, model: Model, options: SolveOptions, hint: np.ndarray | None = None) -> Solution:
        """As :meth:`ProgramBackend.solve`; trip packing first tries the LP with a uniqueness proof.

        Most simulation rounds have one optimum, which the LP relaxation finds and
        :mod:`.unique` proves in a fraction of the MIP's time (its primal heuristics
        alone cost more); rounds with ties or a fractional LP go to the MIP as before.
        ``method = "mip"`` or a positive ``mip_rel_gap`` (which may stop short of the
        optimum) skip the attempt.
        """
        if not (
            model.structure is Structure.TRIP_PACKING
            and model.n_cols
            and options.method in (None, "lp")
            and options.mip_rel_gap == 0
        ):
            return super().solve(model, options, hint)
        self.ensure_installed()
        clock = Clock()
        with clock("solve_s"):
            h = kept_instance(highs_settings(options, options.time_limit_s, relax=True), role="packing_lp", lp=True)
            chosen = run_interruptibly(h, lambda: unique_optimum(model, h))
        if chosen is None:
            sol = super().solve(model, options, hint)
            return replace(sol, solve_s=sol.solve_s + clock.times["solve_s"])
        sol = make_solution(model, chosen, Status.OPTIMAL, self.name, unique=True, **clock.times)
        return replace(sol, bound=sol.objective, gap=0.0)

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
        import highspy

        with clock("build_s"):
            h = kept_instance(highs_settings(options, time_limit, relax=relax), lp=relax)
            n, m = prog.n, prog.n_rows
            inf = highspy.kHighsInf
            integrality = np.full(n, 0 if relax else int(highspy.HighsVarType.kInteger), dtype=np.int32)
            status = h.passModel(
                n,
                m,
                len(prog.indices),
                int(highspy.MatrixFormat.kColwise),
                int(highspy.ObjSense.kMaximize),
                0.0,
                prog.c,
                np.zeros(n),
                np.ones(n),
                np.where(np.isfinite(prog.lo), prog.lo, -inf),
                np.where(np.isfinite(prog.hi), prog.hi, inf),
                prog.indptr.astype(np.int32),
                prog.indices.astype(np.int32),
                np.ones(len(prog.indices), dtype=np.float64),
                integrality,
            )
            if status.name == "kError":
                raise SolverError("HiGHS rejected the model passed by rpbench (passModel returned kError)")
            if hint is not None and not relax:
                h.setSolution(n, np.arange(n, dtype=np.int32), np.asarray(hint, dtype=np.float64))
        with clock("solve_s"):
            run_interruptibly(h)
        with clock("extract_s"):
            status = h.getModelStatus().name
            state = raw_state(STATUS, status, "HiGHS")
            # single info values: h.getInfo() copies every field (~30 µs, a tenth of a typical round's solve)
            has_x = _info(h, "primal_solution_status") == 2  # kSolutionStatusFeasible
            x = np.asarray(h.getSolution().col_value, dtype=np.float64) if has_x else None
            if relax:
                bound = _info(h, "objective_function_value") if state == OPTIMAL else None
            else:
                bound = _info(h, "mip_dual_bound")
        return Raw(x=x, state=state, bound=bound, message="" if state == OPTIMAL else f"HiGHS status {status}")


def _info(h, name: str):
    """One value of HiGHS's info record."""
    status, value = h.getInfoValue(name)
    if status.name == "kError":  # pragma: no cover - names are HiGHS's own
        raise SolverError(f"HiGHS has no info value {name!r}")
    return value
