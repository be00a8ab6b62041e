"""What a command prints besides its table: the command line it records, JSON, and one-line notes on
stderr (among them what a harness :class:`~rpbench.harness.outcome.Outcome` says of its runs).
"""

from __future__ import annotations

import json
import shlex
import sys
from typing import Any

from rpbench.harness.outcome import Outcome
from rpbench.results import to_jsonable
from rpbench.results.runs import run_label


def command_line() -> str | None:
    """The command as typed (recorded in results folders)."""
    return "rpbench " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv else None


def print_json(obj: Any) -> None:
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def note(message: str) -> None:
    """A one-line remark for humans, on stderr (never pollutes --json output)."""
    print(message, file=sys.stderr)


def note_outcome(outcome: Outcome) -> dict[str, str]:
    """One note line per run of the outcome's folder (and of each day, point or unit below it) that rests on
    solver answers not proven optimal or has rounds over the decision budget; returns every unproven run with
    its first reason (to mark table columns)."""
    for where, kind, run, why in outcome.remarks():
        place = f"{where}: " if where else ""
        if kind == "unproven":
            note(
                f"rpbench: note: {place}{run_label(run)} {why}; its numbers are not proven optimal "
                "(--strict makes this an error)"
            )
        else:
            note(f"rpbench: note: {place}{run}: {why}")
    return outcome.unproven_runs()
