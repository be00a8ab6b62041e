"""``rpbench run``: simulate strategies on a scenario, print the comparison, write a results folder."""

from __future__ import annotations

import argparse

from rpbench.commands._figures import add_figures_arg, formats_of
from rpbench.commands._runs import add_run_args, check_presets, parse_runs, run_spec
from rpbench.commands.args import (
    WORKERS,
    add_number_arg,
    add_scenario_args,
    check_numbers,
    decision_budget,
    progress_of,
    scenario_request,
)
from rpbench.commands.checks import check_date_list, check_out_name, check_parallel, check_unique
from rpbench.commands.output import note, note_outcome, print_json
from rpbench.data.first_run import FETCH_COMMAND
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.multiday import mean_bracket_lines, run_days
from rpbench.report.comparison import fmt, text_table
from rpbench.results.layout import REPORT_HTML
from rpbench.results.parents import bracket_by_day
from rpbench.results.ratios import bracket_line, bracket_record
from rpbench.results.runs import run_styles
from rpbench.results.store import check_new_folder, read_meta
from rpbench.spec import RunSpec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "run",
        help="simulate strategies and compare them (the paper's Table 2)",
        description="Simulate dispatching strategies on a scenario, print the comparison table "
        "(strategies as columns) and write a new results folder.",
    )
    add_scenario_args(p)
    add_run_args(p)
    p.add_argument("--out", default=None, help="results folder to create (default ./rpbench-runs/<stamp>_...)")
    p.add_argument("--json", action="store_true", help="print the KPI table as one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_figures_arg(p)
    p.add_argument(
        "--dates",
        default=None,
        metavar="A..B|A,B,...",
        help="run several days of a dated scenario (haikou-peak, haikou-day), e.g. 2017-05-01..2017-05-14",
    )
    add_number_arg(
        p,
        "--workers",
        WORKERS,
        help="parallel worker processes for --dates (default: one per core; 1 = in this process)",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="run --dates on an existing Dask cluster (e.g. tcp://host:8786) instead of local worker "
        "processes (needs the dask extra: pip install 'rpbench[dask]')",
    )
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before anything runs or downloads
    formats_of(args)
    if args.dates and args.date:
        raise ParameterError("--dates and --date exclude each other; drop --date")
    if not args.dates and (args.workers is not None or args.scheduler is not None):
        flag = "--workers" if args.workers is not None else "--scheduler"
        raise ParameterError(f"{flag} spreads the days of --dates; a run of one day runs in this process")
    check_parallel(args)
    check_date_list("--dates", args.dates)
    decision_budget(args)
    runs = parse_runs(args.strategies, args.opt)  # names and options checked before any download
    check_presets(args)
    days = ["2017-05-01"] if args.dates else []  # a day folder's name: a date
    check_out_name(args.out, inner=[*days, "runs", max((e.name for e in runs), key=len)])
    check_new_folder(args.out)  # before a first run's data download: a bad --out must cost nothing
    spec = run_spec(args, scenario_request(args).resolved(), runs=runs)
    code = _run_many_days(args, spec) if args.dates else _run_one(args, spec)
    if args.scenario is None and spec.request.name == "toy" and not args.json:  # the fall-back city
        note(f"rpbench: SYNTHETIC DATA: the table above is the toy city, not Haikou; get the data: {FETCH_COMMAND}")
    return code


def _run_one(args: argparse.Namespace, spec: RunSpec) -> int:
    scenario = spec.request.build()
    note(scenario.label)
    outcome = run_comparison(spec, args.out, scenario=scenario, progress=progress_of(args))
    folder, table = outcome.folder, outcome.table
    unproven = note_outcome(outcome)
    simulated = [e.name for e in spec.simulated]
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "scenario": scenario.label,
                "kpis": {col: table[col].to_dict() for col in table.columns},
                **bracket_record(table, simulated),
                "unproven": unproven,
            }
        )
        return 0
    title = f"{scenario.label} — solver preset {spec.preset}"
    styles = run_styles(read_meta(folder))
    print(text_table(table, title=title, unproven=unproven, styles=styles))
    bracket = bracket_line(table, simulated, fmt, styles)
    if bracket:
        print(bracket)
    print(f"\nresults written to {folder}  (verify: rpbench check {folder})")
    print(f"open {folder / REPORT_HTML} in a browser for the interactive report and the map")
    return 0


def _run_many_days(args: argparse.Namespace, spec: RunSpec) -> int:
    dates = spec.request.dates(args.dates)
    check_unique(f"--dates {args.dates!r}", dates)
    name = spec.request.name
    note(f"running {len(dates)} days of {name} ({dates[0]} .. {dates[-1]}) x {', '.join(spec.names)}")
    outcome = run_days(
        spec,
        dates,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=progress_of(args),
    )
    folder, mean = outcome.folder, outcome.table
    unproven = note_outcome(outcome)
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "dates": dates,
                "unproven": unproven,
                "mean_kpis": {col: mean[col].to_dict() for col in mean.columns},
                "per_day": {
                    day.folder.name: {c: day.table[c].to_dict() for c in day.table.columns} for day in outcome.children
                },
                "bracket_per_day": bracket_by_day(folder).set_index("date").to_dict(orient="index"),
            }
        )
        return 0
    title = f"Mean over {len(dates)} days of {name} ({dates[0]} .. {dates[-1]}), solver preset {spec.preset}"
    print(text_table(mean, title=title, unproven=unproven, styles=run_styles(read_meta(folder / dates[0]))))
    for line in mean_bracket_lines(bracket_by_day(folder))[:1]:
        print(line)
    print(f"\nresults written to {folder}  (per-day folders inside; report: {folder / 'report.md'})")
    print(f"open {folder / REPORT_HTML} in a browser for the interactive report, linking every day's")
    return 0
