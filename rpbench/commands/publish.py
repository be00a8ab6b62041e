"""``rpbench publish SRC DEST``: a checked light copy of a results folder (for ``results/``)."""

from __future__ import annotations

import argparse

from rpbench.harness.publish import HEAVY, publish


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("publish", help="write a checked light copy of a results folder",
                       description="Run rpbench check on a results folder (run, multi-day or sweep) and, if every "
                                   f"check passes, copy it without {', '.join(HEAVY)} and with the checker's "
                                   "verdict in check.txt.")
    p.add_argument("source", metavar="RESULTS_DIR")
    p.add_argument("dest", metavar="DEST", help="folder to create (never overwritten)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    print(publish(args.source, args.dest))
    return 0
