"""Machinery shared by the backends: timing, the generic 0/1 program, status rules, checks.

Every adapter declares a *status map* (its solver's status names -> the raw
states below) read by :func:`raw_state`, and returns solutions through
:func:`finish`, which checks that the solver's values are integral and turns
its raw outcome into a :class:`~rpbench.model.Status` with the same rules
everywhere (feasibility is verified once, by :func:`rpbench.backends.solve`):

* values are integral, so a dual bound ``< objective + 1`` proves the
  incumbent optimal even when a time limit stopped the solver;
* a solve stopped by the time limit returns its incumbent as ``TIME_LIMIT``;
  without an incumbent, packing and pairing return ``x = 0`` (always
  feasible) and the assignment raises :class:`SolverError` (it has no
  trivially feasible answer);
* a solver that answers with a non-integral ``x`` raises
  :class:`SolverError` — never a silently wrong answer.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from rpbench.exceptions import SolverError
from rpbench.model import (
    AssignmentModel,
    Model,
    PairingModel,
    Solution,
    Status,
    Structure,
    TripPackingModel,
    make_solution,
)

#: Raw solver outcomes: proven optimal, stopped by a limit, or proven infeasible.
OPTIMAL, LIMIT, INFEASIBLE = "optimal", "limit", "infeasible"
#: Largest deviation of a "binary" solver value from 0/1 accepted as integral.
INT_TOL = 1e-6


class Clock:
    """Accumulates wall time per phase (``build_s``, ``solve_s``, ``extract_s``)."""

    def __init__(self) -> None:
        self.times = {"build_s": 0.0, "solve_s": 0.0, "extract_s": 0.0}
        self.start = time.perf_counter()

    def __call__(self, phase: str) -> _Phase:
        """A ``with`` block whose wall time is added to ``phase`` (also when it raises)."""
        return _Phase(self.times, phase)

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def remaining(self, limit: float | None) -> float | None:
        return None if limit is None else max(0.0, limit - self.elapsed())


class _Phase:
    """One timed block of a :class:`Clock` (a plain context manager: a round times three of them, and a
    generator-based one cost more than the little it times)."""

    __slots__ = ("phase", "t0", "times")

    def __init__(self, times: dict[str, float], phase: str) -> None:
        self.times, self.phase = times, phase

    def __enter__(self) -> None:
        self.t0 = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.times[self.phase] += time.perf_counter() - self.t0


@dataclass(frozen=True)
class Program:
    """``maximise c·x  s.t.  lo <= A x <= hi,  x ∈ {0,1}^n`` (or ``[0,1]^n`` relaxed).

    ``A`` is the model's 0/1 incidence matrix, optionally with one extra row
    ``Σ x >= k`` (the cardinality stage of Oracle-2), kept as CSC index arrays
    (rows sorted within each column); adapters that want a scipy matrix read
    :attr:`A`, built on first use (a simulation round, solved by HiGHS from the
    arrays, then never pays for scipy's construction checks).
    """

    c: np.ndarray
    indptr: np.ndarray  # column starts, n + 1 entries
    indices: np.ndarray  # row of each nonzero
    lo: np.ndarray
    hi: np.ndarray

    @property
    def n(self) -> int:
        return len(self.indptr) - 1

    @property
    def n_rows(self) -> int:
        return len(self.lo)

    @cached_property
    def A(self) -> sp.csc_matrix:
        data = np.ones(len(self.indices), dtype=np.float64)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n_rows, self.n))


_ROWS_SORTED = (AssignmentModel, TripPackingModel, PairingModel)


def program(model: Model, c: np.ndarray | None = None, min_count: int | None = None) -> Program:
    """The model as a 0/1 program; ``c`` defaults to its values."""
    exact = model.row_exact()
    lo = np.where(exact, 1.0, -np.inf)
    hi = np.ones(model.n_rows)
    start, rows = model.column_rows()
    # The built-in models' validation orders each column's rows (passenger < vehicle rows, a < b):
    # only another class's need checking.
    if min_count is not None or (type(model) not in _ROWS_SORTED and not _sorted_within_columns(start, rows)):
        A = model.incidence()
        if min_count is not None:
            A = sp.vstack([A, sp.csr_matrix(np.ones((1, model.n_cols)))], format="csc")
            lo, hi = np.append(lo, float(min_count)), np.append(hi, np.inf)
        A.sort_indices()
        start, rows = A.indptr, A.indices
    return Program(
        c=np.asarray(model.values if c is None else c, dtype=np.float64), indptr=start, indices=rows, lo=lo, hi=hi
    )


def _sorted_within_columns(start: np.ndarray, rows: np.ndarray) -> bool:
    """Whether the CSC row indices increase strictly within every column (as scipy's sorted form)."""
    if len(rows) < 2:
        return True
    rising = rows[1:] > rows[:-1]
    rising[start[1:-1][(start[1:-1] > 0) & (start[1:-1] < len(rows))] - 1] = True  # column boundaries
    return bool(rising.all())


@dataclass
class Raw:
    """A solver's answer before checking: ``x`` (``None`` = no incumbent), state, dual bound."""

    x: np.ndarray | None
    state: str
    bound: float | None = None
    message: str = ""
    extra: dict = field(default_factory=dict)


def raw_state(status_map: dict, status, solver: str) -> str:
    """A solver status as a raw state through the adapter's status map; an unmapped status is an error."""
    state = status_map.get(status)
    if state is None:
        raise SolverError(f"{solver} ended with status {status!r}")
    return state


# ------------------------------------------------------------------ checks
def chosen_columns(model: Model, x: np.ndarray, backend: str) -> np.ndarray:
    """Indices of the columns set to 1, after checking that the values are integral."""
    from rpbench.model import kernels  # compiled on first use

    x = np.asarray(x, dtype=np.float64)
    if x.shape != (model.n_cols,):
        raise SolverError(f"backend {backend!r} returned {x.shape} values for {model.n_cols} columns of {model.name!r}")
    worst, c, chosen = kernels.integral_support(x)
    if worst > INT_TOL:  # NaN passes, as it did np.max's comparison; feasibility is verified by solve()
        raise SolverError(f"backend {backend!r} returned a fractional value x[{c}] = {x[c]!r} on {model.name!r}")
    return chosen


def integral_bound(bound: float | None) -> float | None:
    """A solver's dual bound rounded down to the integral grid of the values (with a tolerance)."""
    if bound is None or not math.isfinite(bound):
        return None
    return float(math.floor(bound + 1e-6 * max(1.0, abs(bound))))


def classify(state: str, objective: float, bound: float | None, rel_gap: float) -> Status:
    """Status of an incumbent from the solver's state and its (integral) bound."""
    proven = bound is not None and bound <= objective
    if state == OPTIMAL:
        return Status.FEASIBLE if (rel_gap > 0 and bound is not None and not proven) else Status.OPTIMAL
    return Status.OPTIMAL if proven else Status.TIME_LIMIT


def finish(
    model: Model,
    raw: Raw,
    backend: str,
    clock: Clock,
    rel_gap: float = 0.0,
    message: str = "",
    *,
    chosen: np.ndarray | None = None,
) -> Solution:
    """Check a raw answer and wrap it as a :class:`Solution` (see the module docstring).

    ``chosen``: the columns ``raw.x`` sets to 1 when the caller has read them already, its values found
    integral within :data:`INT_TOL` (as :func:`chosen_columns` checks them).
    """
    note = "; ".join(m for m in (message, raw.message) if m)
    if raw.state == INFEASIBLE:
        if model.structure is not Structure.ASSIGNMENT:
            raise SolverError(f"backend {backend!r} reports {model.name!r} infeasible, but x = 0 is feasible")
        return make_solution(
            model, np.zeros(0, np.int64), Status.INFEASIBLE, backend, message=note or "infeasible", **clock.times
        )
    if raw.x is None:
        if raw.state == OPTIMAL:
            raise SolverError(f"backend {backend!r} reports an optimum of {model.name!r} but returned no solution")
        if model.structure is Structure.ASSIGNMENT:
            raise SolverError(
                f"backend {backend!r} stopped on {model.name!r} (time limit) before finding any "
                "feasible assignment; raise time_limit_s or use a faster preset (matching, ortools)"
            )
        chosen = np.zeros(0, np.int64)
        note = note or "time limit before any incumbent: returning x = 0"
    elif chosen is None or np.shape(raw.x) != (model.n_cols,):
        chosen = chosen_columns(model, raw.x, backend)
    objective = model.objective_of(chosen)
    bound = integral_bound(raw.bound)
    if bound is not None and bound < objective:
        bound = None  # inconsistent with the incumbent: proves nothing, report nothing
    status = classify(raw.state, objective, bound, rel_gap)
    if status is Status.OPTIMAL:
        bound = objective
    gap = None if bound is None else (bound - objective) / max(1.0, abs(objective))
    return make_solution(model, chosen, status, backend, bound=bound, gap=gap, message=note, **clock.times)
