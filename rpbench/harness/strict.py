"""Strict mode: refuse every answer a solver did not prove optimal (``--strict``).

A preset's time limit (or a relative gap) can stop a round's model or an
oracle before its optimum is proven.  By default the run goes on with the
incumbent, the terminal says so in one note line per run and the report
marks the run (:func:`rpbench.results.report.unproven_runs`).  In strict
mode such a stop is a :class:`~rpbench.exceptions.SolverError` instead and
nothing is written.

The switch is a process-wide policy, not only an argument, because
multi-day runs and sweeps reach
:func:`~rpbench.harness.comparison.run_comparison` through worker tasks;
:func:`rpbench.harness.parallel.run_tasks` carries the caller's policy to
the workers.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from rpbench.exceptions import SolverError

#: What a user can do about an unproven solve (shared by every message about one).
ADVICE = "raise the preset's time_limit_s (solvers/NAME.toml, --time-limit) or choose a faster exact preset"

_strict = False


def is_strict() -> bool:
    """Whether the current command asked for ``--strict``."""
    return _strict


@contextlib.contextmanager
def strict_mode(on: bool = True) -> Iterator[None]:
    """Run the body with strict mode ``on`` (restored afterwards, so in-process callers such as tests
    do not leak it into later commands)."""
    global _strict
    previous, _strict = _strict, bool(on)
    try:
        yield
    finally:
        _strict = previous


def require_proven(what: str, status: str, *, strict: bool | None = None) -> None:
    """In strict mode (``strict``, default the policy), raise unless ``status`` (a solver status value)
    is ``optimal``."""
    if (_strict if strict is None else strict) and status != "optimal":
        raise SolverError(f"{what} stopped with status {status}, not proven optimal (--strict); {ADVICE}")
