"""``rpbench evaluate PROTOCOL``: a fixed protocol's runs over days and seeds, and its leaderboard."""

from __future__ import annotations

import argparse

from rpbench.commands._figures import add_figures_arg, formats_of
from rpbench.commands.args import (
    add_data_arg,
    add_decision_budget_arg,
    add_offline_arg,
    add_parallel_args,
    check_numbers,
    decision_budget,
    progress_of,
)
from rpbench.commands.checks import check_out_name, check_parallel
from rpbench.commands.output import command_line, note, note_outcome
from rpbench.data.first_run import ensure_data_dir
from rpbench.harness.evaluate import run_evaluation
from rpbench.protocols import builtin_names, load_protocol
from rpbench.results.layout import REPORT, REPORT_HTML
from rpbench.scenarios import scenario_spec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="run a named evaluation protocol (days x seeds) and rank the strategies with intervals",
        description="Run every (day, seed) comparison of a protocol, in parallel, and write its leaderboard: "
        "per strategy the mean of each metric with a bootstrap interval, and paired differences with "
        "Wilcoxon tests. Run again on the same --out to resume what is missing. Built-in protocols: "
        + ", ".join(builtin_names())
        + " (or a path to a protocol TOML file).",
    )
    p.add_argument("protocol", metavar="PROTOCOL", help="a built-in protocol name or a protocol .toml file")
    p.add_argument("--out", default=None, help="evaluation folder (an existing one of the same protocol is resumed)")
    add_parallel_args(p)
    add_decision_budget_arg(p)
    add_data_arg(p)
    add_offline_arg(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_figures_arg(p)
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before anything runs or downloads
    formats = formats_of(args)
    check_parallel(args)
    budget = decision_budget(args)
    check_out_name(args.out)
    protocol = load_protocol(args.protocol)
    data = None
    spec = scenario_spec(protocol.scenario)
    if spec.needs_data:
        what = f"protocol {protocol.name!r}"
        data = str(ensure_data_dir(args.data, what=what, offline=args.offline, city=spec.city))
    outcome = run_evaluation(
        protocol,
        args.out,
        data_dir=data,
        workers=args.workers,
        scheduler=args.scheduler,
        command=command_line(),
        decision_budget_s=budget,
        progress=progress_of(args),
        formats=formats,
    )
    folder, ran = outcome.folder, sum(unit.fresh for unit in outcome.children)
    note_outcome(outcome)
    total = len(outcome.children)
    if ran == total:
        note(f"{total} unit(s) of the protocol run")
    elif ran:
        note(f"{ran} of {total} unit(s) run now; the others were already in the folder (resumed)")
    else:
        note(f"every one of the {total} unit(s) was already in the folder: nothing to run")
    print((folder / REPORT).read_text())
    print(f"results written to {folder}  (verify: rpbench check {folder}; in a browser: {folder / REPORT_HTML})")
    return 0
