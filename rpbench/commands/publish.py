"""``rpbench publish SRC DEST``: a checked light copy of a results folder (for ``results/``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rpbench.exceptions import ResultsError, RpbenchError
from rpbench.results.layout import HEAVY
from rpbench.results.store import check_new_folder


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "publish",
        help="write a checked light copy of a results folder",
        description="Run rpbench check on a results folder (run, multi-day or sweep) and, if every "
        f"check passes, copy it without {', '.join(HEAVY)} and with the checker's "
        "verdict in check.txt.  The folder is first copied whole beside DEST and the checker runs on that "
        "copy, so what is published is what was checked.  A folder holding a symbolic link (or a special "
        "file) is refused: publish copies files, never what a link points to.  Only one publish to a "
        "DEST runs at a time; a second one fails at once.",
    )
    p.add_argument("source", metavar="RESULTS_DIR")
    p.add_argument("dest", metavar="DEST", help="folder to create (never overwritten)")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    from rpbench.harness.publish import publish  # with the checker: only when publishing

    dest = Path(args.dest)
    # before the (slow) checker: DEST must be free (a dangling link counts as taken) and its folder writable
    check_new_folder(dest, what="DEST")
    try:
        print(publish(args.source, dest))  # removes its own staging folder, whatever stops it
    except OSError as exc:
        if isinstance(exc, RpbenchError):
            raise
        where = f"{exc.filename}: " if exc.filename else ""
        raise ResultsError(
            f"cannot publish to {str(dest)!r} ({where}{exc.strerror or exc}); nothing was written"
        ) from None
    return 0
