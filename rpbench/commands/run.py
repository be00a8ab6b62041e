"""``rpbench run``: simulate strategies on a scenario, print the comparison, write a results folder."""

from __future__ import annotations

import argparse

import pandas as pd

from rpbench.commands._common import (
    add_scenario_args,
    add_strict_arg,
    command_line,
    note,
    note_unproven,
    print_json,
    scenario_request,
)
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import parse_run_options, parse_strategies, run_comparison
from rpbench.harness.multiday import run_days
from rpbench.harness.strict import strict_mode
from rpbench.results.report import load_kpis, text_table
from rpbench.results.store import check_new_folder
from rpbench.scenarios import ScenarioRequest

DEFAULT_STRATEGIES = "np,mb,rtv,fl-nd,fl,bound,oracle1,oracle2"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "run",
        help="simulate strategies and compare them (the paper's Table 2)",
        description="Simulate dispatching strategies on a scenario, print the comparison table "
        "(strategies as columns) and write a new results folder.",
    )
    add_scenario_args(p)
    p.add_argument(
        "--strategies",
        default=DEFAULT_STRATEGIES,
        help=f"comma-separated strategies and oracles (default {DEFAULT_STRATEGIES})",
    )
    p.add_argument("--solver", default="highs", help="solver preset, solvers/NAME.toml (default highs)")
    p.add_argument(
        "--oracle-solver",
        default=None,
        metavar="PRESET",
        help="preset for Oracle-1/Oracle-2 (default: --solver; `matching` is the fastest exact one)",
    )
    p.add_argument(
        "--opt",
        action="append",
        default=[],
        metavar="STRATEGY.KEY=VALUE",
        help="strategy option, e.g. --opt rtv.c_ko=large (repeatable; `rpbench list` names them)",
    )
    p.add_argument("--out", default=None, help="results folder to create (default ./rpbench-runs/<stamp>_...)")
    p.add_argument("--json", action="store_true", help="print the KPI table as one JSON object")
    add_strict_arg(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--dates",
        default=None,
        metavar="A..B|A,B,...",
        help="run several days of a dated scenario (haikou-peak, haikou-day), e.g. 2017-05-01..2017-05-14",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="parallel worker processes for --dates (default: one per core; 1 = in this process)",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="run --dates on an existing Dask cluster (e.g. tcp://host:8786) instead of local worker "
        "processes (needs the dask extra: pip install 'rpbench[dask]')",
    )
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    strategies = parse_strategies(args.strategies)
    run_options = parse_run_options(args.opt, strategies)
    request = scenario_request(args)
    check_new_folder(args.out)  # before simulating: a bad --out must not cost the whole run
    with strict_mode(args.strict):
        if args.dates:
            return run_many_days(args, request, strategies, run_options)
        return run_one(args, request, strategies, run_options)


def run_one(args: argparse.Namespace, request: ScenarioRequest, strategies: list[str], run_options: dict) -> int:
    scenario = request.build()
    note(scenario.label)
    folder, table = run_comparison(
        scenario,
        strategies,
        args.solver,
        out=args.out,
        run_options=run_options,
        progress=False if args.no_progress else None,
        request=request,
        command=command_line(),
        oracle_solver=args.oracle_solver,
    )
    unproven = note_unproven(folder)
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "scenario": scenario.label,
                "kpis": {col: table[col].to_dict() for col in table.columns},
                "unproven": unproven,
            }
        )
        return 0
    print(text_table(table, title=f"{scenario.label} — solver preset {args.solver}", unproven=unproven))
    print(f"\nresults written to {folder}  (verify: rpbench check {folder})")
    return 0


def run_many_days(args: argparse.Namespace, request: ScenarioRequest, strategies: list[str], run_options: dict) -> int:
    if args.date:
        raise ParameterError("--dates and --date exclude each other; drop --date")
    dates = request.dates(args.dates)
    note(f"running {len(dates)} days of {request.name} ({dates[0]} .. {dates[-1]}) x {', '.join(strategies)}")
    folder = run_days(
        request,
        dates,
        strategies=strategies,
        preset=args.solver,
        run_options=run_options,
        out=args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        command=command_line(),
        oracle_solver=args.oracle_solver,
    )
    summary = pd.read_csv(folder / "summary.csv")
    mean = summary.pivot(index="kpi", columns="run", values="mean")[[s for s in strategies]]
    unproven = note_unproven(folder)
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "dates": dates,
                "unproven": unproven,
                "mean_kpis": {col: mean[col].to_dict() for col in mean.columns},
                "per_day": {d: {c: t[c].to_dict() for c in t.columns} for d in dates for t in [load_kpis(folder / d)]},
            }
        )
        return 0
    print(
        text_table(
            mean,
            title=f"Mean over {len(dates)} days of {request.name} ({dates[0]} .. {dates[-1]}), "
            f"solver preset {args.solver}",
            unproven=unproven,
        )
    )
    print(f"\nresults written to {folder}  (per-day folders inside; report: {folder / 'report.md'})")
    return 0
