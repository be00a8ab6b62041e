"""``rpbench check RESULTS_DIR``: re-verify every run of a results folder from its event log."""

from __future__ import annotations

import argparse

from rpbench.commands._common import print_json
from rpbench.results.check import check_folder, format_report
from rpbench.results.store import run_folders


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="verify a results folder from its event logs",
                       description="Re-verify every run of results folders from their event logs alone; exit "
                                   "status 1 when any check fails, naming it.")
    p.add_argument("folders", nargs="+", metavar="RESULTS_DIR",
                   help="results folders; a multi-day or sweep folder checks every run folder inside it")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    failed = False
    report = {}
    folders = [str(f) for given in args.folders for f in run_folders(given)]
    for folder in folders:
        checks = check_folder(folder)
        failed |= any(not c.ok for c in checks)
        report[folder] = {c.run: {"ok": c.ok, "violations": c.violations, "checked": c.checked} for c in checks}
        if not args.json:
            if len(folders) > 1:
                print(f"== {folder}")
            print(format_report(checks))
    if args.json:
        print_json({"ok": not failed, "folders": report})
    return 1 if failed else 0
