"""``rpbench report RESULTS_DIR...``: render reports (markdown + PNG plots) from result files alone."""

from __future__ import annotations

import argparse
from pathlib import Path

from rpbench.commands._common import check_out_file, write_out_file
from rpbench.harness.render import render


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report",
        help="render reports from results folders",
        description="Re-render report.md and plots of results folders (comparisons, multi-day "
        "runs, sweeps) from their files alone; several folders give a combined table.",
    )
    p.add_argument("folders", nargs="+", metavar="RESULTS_DIR")
    p.add_argument("--metrics", default=None, help="comma-separated KPI names for the combined table")
    p.add_argument("--out", default=None, help="write the markdown here instead of printing it")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    metrics = [m.strip() for m in args.metrics.split(",")] if args.metrics else None
    out = check_out_file(args.out, "--out") if args.out else None  # before rendering anything
    text, _ = render([Path(f) for f in args.folders], metrics)
    if out is not None:
        write_out_file(out, "--out", lambda tmp: tmp.write_text(text))
        print(f"report written to {args.out}")
    else:
        print(text)
    return 0
