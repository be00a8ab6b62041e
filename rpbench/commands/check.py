"""``rpbench check RESULTS_DIR``: re-verify a results folder from its own files (docs/guarantees.md); exit status
0 all checks passed, 1 a check failed (named), 2 bad usage or an unreadable folder (one line on stderr)."""

from __future__ import annotations

import argparse
import sys

from rpbench.commands.output import print_json

#: Each exit status of the checker as the word ``--json`` says (0 ok, 1 failed, 2 unreadable:
#: :data:`rpbench.check.EXIT_OK` and the others).
CHECK_STATUS = {0: "ok", 1: "failed", 2: "unreadable"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "check",
        help="verify a results folder from its event logs",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Re-verify every run of results folders from their own files alone: the event "
        "logs,\ntrajectories and oracle pairs against the rules, every reported number "
        "recomputed,\nthe inputs against the digest recorded at run time "
        "(docs/guarantees.md).",
        epilog="exit status:\n"
        "  0  every check passed (checks an older folder cannot support are listed as skipped)\n"
        "  1  a check failed: each failure is named, e.g. [max-detour] or [kpi]\n"
        "  2  bad usage, or a folder is unreadable (a file missing, truncated or unparseable):\n"
        "     one line on stderr; 2 wins over 1 when several folders are given",
    )
    p.add_argument(
        "folders",
        nargs="+",
        metavar="RESULTS_DIR",
        help="results folders; a multi-day or sweep folder checks every run folder inside it",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object: ok, status (ok/failed/unreadable), exit_status, folders (folder -> "
        "run -> ok, status, violations, checked, skipped) and unreadable (folder -> reason)",
    )
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    from rpbench.check import EXIT_OK, check_tree, exit_status, format_report  # the checker: only when checking

    found = [result for given in args.folders for result in check_tree(given)]
    for result in found:
        if len(found) > 1 and not args.json:
            print(f"== {result.folder}", flush=True)
        if result.error is not None:  # the CLI's convention for bad input: one line on stderr
            print(f"rpbench: error: {result.error}", file=sys.stderr)
        elif not args.json:
            print(format_report(result.checks))
    code = exit_status(found)
    if args.json:
        print_json(
            {
                "ok": code == EXIT_OK,
                "status": CHECK_STATUS[code],
                "exit_status": code,
                "folders": {
                    r.folder: {
                        c.run: {
                            "ok": c.ok,
                            "status": c.status,
                            "violations": c.violations,
                            "checked": c.checked,
                            "skipped": c.skipped,
                        }
                        for c in r.checks
                    }
                    for r in found
                },
                "unreadable": {r.folder: r.error for r in found if r.error is not None},
            }
        )
    return code
