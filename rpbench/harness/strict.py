"""Unproven solves: what ``--strict`` refuses.

A preset's time limit (or a relative gap) can stop a round's model or an
offline run before its optimum is proven.  By default the run goes on with
the incumbent, the terminal says so in one note line per run and the report
marks the run (:func:`rpbench.report.comparison.unproven_runs`).  With
:attr:`RunSpec.strict <rpbench.spec.RunSpec.strict>` such a stop is a
:class:`~rpbench.exceptions.SolverError` instead, and nothing is written.
"""

from __future__ import annotations

from rpbench.exceptions import SolverError

#: What a user can do about an unproven solve (shared by every message about one).
ADVICE = "raise the preset's time_limit_s (solvers/NAME.toml, --time-limit) or choose a faster exact preset"


def require_proven(what: str, status: str, *, strict: bool) -> None:
    """With ``strict``, raise unless ``status`` (a solver status value) is ``optimal``."""
    if strict and status != "optimal":
        raise SolverError(f"{what} stopped with status {status}, not proven optimal (--strict); {ADVICE}")
