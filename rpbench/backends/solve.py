"""The one way to solve a model: :func:`solve` (used by the simulator, the oracle and the benchmark).

It checks that the preset's backend is installed and solves the model's
structure exactly, solves, and verifies the answer once — a
:class:`~rpbench.model.Solution` with a known status, its chosen columns
distinct integral indices inside the model, no row over-covered, every
"exactly once" row covered, its reported objective their total value and its
numbers finite — so no caller has to repeat the check, and an adapter
(built-in or plug-in) that answers wrongly is an error naming it, never a
silently wrong or silently corrected result.
"""

from __future__ import annotations

import math
from dataclasses import replace
from numbers import Real

import numpy as np

from rpbench.backends.presets import Preset
from rpbench.exceptions import ModelError, SolverError
from rpbench.model import Model, Solution, Status, Structure, empty_solution

#: Relative tolerance on a reported objective (values are integral, so exact sums agree exactly; a solver's
#: floating-point echo of its objective may differ in the last digits).
OBJECTIVE_RTOL = 1e-9


def solve(model: Model, preset: Preset, *, hint: np.ndarray | None = None) -> Solution:
    """Solve ``model`` with ``preset``; ``hint`` (0/1 per column, feasible) warm-starts backends that take one."""
    backend = preset.require(model.structure)
    if not np.isfinite(model.values).all():
        # Models are checked on construction, but their arrays can be changed afterwards; a NaN sends
        # HiGHS's simplex into a loop that honours neither its time limit nor SIGTERM.
        c = int(np.flatnonzero(~np.isfinite(model.values))[0])
        value = float(model.values[c])
        raise ModelError(f"model {model.name!r}: value of column {c} is {value!r}; values must be finite")
    if model.n_cols == 0:
        return empty_solution(model, backend.name)
    if hint is not None and backend.accepts_hint:
        solution = backend.solve(model, preset.options, hint=hint)  # type: ignore[call-arg]
    else:
        solution = backend.solve(model, preset.options)
    cls = type(backend)
    return verify(model, solution, f"backend {preset.backend!r} ({cls.__module__}.{cls.__qualname__})")


def verify(model: Model, solution: object, solver: str) -> Solution:
    """``solution`` if it is a valid answer of ``model`` (feasible, or an honest infeasible one), with its
    chosen columns as a sorted read-only int64 array; otherwise a :class:`SolverError` naming ``solver``."""
    if not isinstance(solution, Solution):
        what = "None" if solution is None else f"a {type(solution).__name__}"
        raise SolverError(f"{solver} returned {what} on {model.name!r}, not a rpbench.model.Solution")
    if not isinstance(solution.status, Status):
        known = ", ".join(f"Status.{s.name}" for s in Status)
        raise SolverError(f"{solver} returned status {solution.status!r} on {model.name!r}, not one of {known}")
    if solution.status is Status.ERROR:
        raise SolverError(f"{solver} failed on {model.name!r}: {solution.message or 'no message'}")
    chosen = _chosen(model, solution.chosen, solver)
    if solution.status is Status.INFEASIBLE:
        if model.structure is not Structure.ASSIGNMENT:  # x = 0 is feasible for packing and pairing
            raise SolverError(f"{solver} reports {model.name!r} infeasible, but x = 0 is feasible")
        return solution
    problems = model.violations(chosen)
    if problems:
        raise SolverError(f"{solver} returned an infeasible solution of {model.name!r}: {problems[0]}")
    exact = model.objective_of(chosen)
    reported = solution.objective
    if not (_finite(reported) and abs(reported - exact) <= OBJECTIVE_RTOL * max(1.0, abs(exact))):
        raise SolverError(
            f"{solver} reports objective {reported!r} on {model.name!r}, but its chosen columns are worth "
            f"{exact:.17g} (the sum of their values)"
        )
    for name, value in (("bound", solution.bound), ("gap", solution.gap)):
        if value is not None and not _finite(value):
            raise SolverError(f"{solver} reports {name} {value!r} on {model.name!r}; expected a finite number or None")
    times = (("build_s", solution.build_s), ("solve_s", solution.solve_s), ("extract_s", solution.extract_s))
    for name, value in times:
        if not (_finite(value) and value >= 0):
            raise SolverError(f"{solver} reports {name} = {value!r} on {model.name!r}; times are seconds >= 0")
    if chosen is solution.chosen:
        return solution
    return replace(solution, chosen=chosen)


def _finite(value: object) -> bool:
    if type(value) is float:  # the usual case, without the abstract-class check
        return math.isfinite(value)
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


def _strictly_increasing(raw: np.ndarray) -> bool:
    """Whether the int64 indices are sorted without repeats (one compiled pass)."""
    from rpbench.model import kernels  # compiled on first use

    return bool(kernels.strictly_increasing(raw))


def _chosen(model: Model, raw: object, solver: str) -> np.ndarray:
    """A solution's chosen columns as sorted read-only int64 indices, or a :class:`SolverError`.

    ``raw`` itself when it is that already (every built-in backend returns it so); the range, duplicates
    and feasibility are :meth:`~rpbench.model._Model.violations`' to check.
    """
    if (
        isinstance(raw, np.ndarray)
        and raw.dtype == np.int64
        and raw.ndim == 1
        and not raw.flags.writeable
        and _strictly_increasing(raw)
    ):
        return raw
    arr = np.asarray(raw)
    if arr.dtype == np.bool_ or arr.ndim != 1 or (len(arr) and arr.dtype.kind not in "iuf"):
        raise SolverError(
            f"{solver} returned chosen columns of shape {arr.shape}, dtype {arr.dtype} on {model.name!r}; a Solution's "
            "chosen holds column indices (for a 0/1 vector x: np.flatnonzero(x > 0.5))"
        )
    if len(arr) > model.n_cols:
        raise SolverError(
            f"{solver} returned {len(arr)} chosen columns for the {model.n_cols} columns of {model.name!r} "
            "(a Solution's chosen holds column indices, not a 0/1 vector)"
        )
    if arr.dtype.kind == "f" and not np.all(arr == np.round(arr)):  # NaN too
        c = int(np.flatnonzero(arr != np.round(arr))[0])
        raise SolverError(f"{solver} returned a fractional chosen column index {float(arr[c])!r} on {model.name!r}")
    out = np.sort(arr.astype(np.int64))
    out.setflags(write=False)
    return out
