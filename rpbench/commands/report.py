"""``rpbench report RESULTS_DIR...``: render reports (markdown + PNG plots, and with ``--html`` the interactive
page) from result files alone; several comparison folders of one scenario combine into one comparison."""

from __future__ import annotations

import argparse
import shutil
import tempfile
from functools import partial
from pathlib import Path

from rpbench.commands._figures import add_figures_arg, formats_of
from rpbench.commands.checks import check_out_file, write_out_file
from rpbench.files import printable, write_text
from rpbench.harness.render import render


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report",
        help="render reports from results folders, or combine comparisons of one scenario",
        description="Re-render the report.md and plots of a results folder (comparison, multi-day "
        "run, sweep) from its files alone. Several comparison folders of one scenario (the same input files "
        "and parameters) combine into one comparison: one table of every run of every folder, a run found in "
        "several folders shown once when it is the same run, else once per folder; it is printed, and "
        "nothing is written in the folders (--out FILE writes it with its figure and tables). Folders of "
        "different scenarios, or a multi-day, sweep or evaluation folder among several, are refused. Figures are "
        "PNG; --figures svg,pdf writes SVG and PDF copies too (into the folder, or beside FILE with --out), "
        "leaving figures of other formats as they are.",
    )
    p.add_argument("folders", nargs="+", metavar="RESULTS_DIR")
    p.add_argument("--metrics", default=None, help="comma-separated KPI names: the table shows only these")
    p.add_argument(
        "--html",
        action="store_true",
        help="also write the folder's report.html, one self-contained interactive page with a map "
        "(runs write it already; a published light copy's page has no map: re-render the full folder); "
        "one folder only",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="write the markdown to FILE, and its plots (PNG; SVG, PDF with --figures), tables (table.tex, "
        "table.csv) and page beside it as FILE's name + '-' + the file's name, "
        "instead of printing it; the results folders are then left as they are (several folders: the "
        "combined table and its headline-KPI figure)",
    )
    add_figures_arg(p, later=False)
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    formats = formats_of(args)  # before anything is written
    metrics = [m.strip() for m in args.metrics.split(",")] if args.metrics else None
    if args.out is None:
        text, _ = render([Path(f) for f in args.folders], metrics, page=args.html, formats=formats)
        print(printable(text))
        return 0
    out = check_out_file(args.out, "--out")  # before rendering anything
    plots: list[Path] = []
    try:
        with tempfile.TemporaryDirectory(prefix="rpbench-report-") as tmp:
            text, _ = render([Path(f) for f in args.folders], metrics, dest=Path(tmp), page=args.html, formats=formats)
            for png in sorted(p for p in Path(tmp).iterdir() if p.is_file() and p.name != "report.md"):
                target = out.with_name(f"{out.stem}-{png.name}")
                write_out_file(target, "--out", partial(shutil.copyfile, png))
                plots.append(target)
                text = text.replace(f"]({png.name})", f"]({target.name})")  # the report's links follow the plots
        write_out_file(out, "--out", lambda tmp: write_text(tmp, text))
    except BaseException:  # a report written in part is not written: its plots go too
        for target in plots:
            target.unlink(missing_ok=True)
        raise
    beside = f" (plots beside it: {', '.join(p.name for p in plots)})" if plots else ""
    print(printable(f"report written to {args.out}{beside}"))
    return 0
