"""``rpbench publish SRC DEST``: a checked light copy of a results folder (for ``results/``)."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from rpbench.exceptions import ResultsError, RpbenchError
from rpbench.harness.publish import HEAVY, publish
from rpbench.results.store import check_new_folder


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "publish",
        help="write a checked light copy of a results folder",
        description="Run rpbench check on a results folder (run, multi-day or sweep) and, if every "
        f"check passes, copy it without {', '.join(HEAVY)} and with the checker's "
        "verdict in check.txt.",
    )
    p.add_argument("source", metavar="RESULTS_DIR")
    p.add_argument("dest", metavar="DEST", help="folder to create (never overwritten)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    dest = Path(args.dest)
    # before the (slow) checker: DEST must be free (a dangling link counts as taken) and its folder writable
    check_new_folder(dest, what="DEST")
    try:
        print(publish(args.source, dest))
    except BaseException as exc:
        _remove_staging(dest)
        if isinstance(exc, OSError) and not isinstance(exc, RpbenchError):
            where = f"{exc.filename}: " if exc.filename else ""
            raise ResultsError(
                f"cannot publish to {str(dest)!r} ({where}{exc.strerror or exc}); nothing was written"
            ) from None
        raise
    return 0


def _remove_staging(dest: Path) -> None:
    """The copy rpbench.harness.publish stages beside DEST before renaming it into place."""
    staging = dest.with_name(f".{dest.name}.partial")
    if staging.is_dir() and not staging.is_symlink():
        shutil.rmtree(staging, ignore_errors=True)
