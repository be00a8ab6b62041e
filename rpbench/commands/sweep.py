"""``rpbench sweep``: parameter sweeps in the layout of the paper's Tables 3-6."""

from __future__ import annotations

import argparse

from rpbench.commands._figures import add_figures_arg, formats_of
from rpbench.commands._runs import add_run_args, check_presets, parse_runs, run_spec, split_list
from rpbench.commands.args import (
    GivenOnce,
    add_parallel_args,
    add_scenario_args,
    check_numbers,
    decision_budget,
    parse_param_overrides,
    progress_of,
    scenario_request,
)
from rpbench.commands.checks import check_out_name, check_parallel
from rpbench.commands.output import note, note_outcome, print_json
from rpbench.exceptions import ParameterError
from rpbench.harness.sweep import SWEEPS, SweepSpec, expand, option_target, parse_over, run_sweep
from rpbench.results.layout import REPORT_HTML
from rpbench.results.store import check_new_folder


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="parameter sweeps (the paper's Tables 3-6)",
        description="Run a parameter sweep: a predefined one of the paper "
        f"({', '.join(SWEEPS)}) or --over NAME=V1,V2,...; points run in parallel "
        "in local worker processes (or on an existing Dask cluster, --scheduler).",
    )
    p.add_argument("sweep", nargs="?", choices=list(SWEEPS), help="predefined sweep")
    p.add_argument(
        "--over",
        default=None,
        action=GivenOnce,
        metavar="NAME=V1,V2,...",
        help="sweep any scenario parameter instead, or a run's option as RUN.OPTION=V1,V2,... "
        "(e.g. fl.tau0_s=60,120,240)",
    )
    p.add_argument("--values", default=None, help="override a predefined sweep's values, e.g. 60,90,120")
    add_scenario_args(p)
    add_run_args(p, strategies=None)
    p.add_argument("--out", default=None, help="sweep folder to create")
    add_parallel_args(p)
    p.add_argument("--json", action="store_true", help="print the sweep table as one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_figures_arg(p)
    p.set_defaults(handler=_run)


def build_spec(args: argparse.Namespace) -> SweepSpec:
    if (args.sweep is None) == (args.over is None):
        raise ParameterError(f"give either a predefined sweep ({', '.join(SWEEPS)}) or --over NAME=V1,V2,...")
    if args.over:
        if args.values:
            raise ParameterError(
                "--values changes a predefined sweep's values; with --over give them as NAME=V1,V2,..."
            )
        parameter, over = parse_over(args.over)
        strategies = tuple(split_list(args.strategies or "mb,rtv,fl"))
        return SweepSpec(
            name=parameter,
            parameter=parameter,
            values=tuple(over),
            strategies=strategies,
            kpis=("avg_detour_m", "total_saving_km", "avg_response_time_s", "response_rate", "pairing_ratio"),
        )
    spec = SWEEPS[args.sweep]
    values = tuple(parse_over(f"{spec.parameter}={args.values}")[1]) if args.values else spec.values
    strategies = tuple(split_list(args.strategies)) if args.strategies else spec.strategies
    return SweepSpec(spec.name, spec.parameter, values, strategies, spec.kpis, spec.paper_table)


def check_opt_conflict(parameter: str, runs: list[str], opts: list[str]) -> None:
    """``--opt RUN.OPTION=V`` beside a sweep over that same option is an error: every point sets it."""
    target = option_target(parameter, runs)
    if target is None:
        return
    for item in opts:
        key = item.partition("=")[0].strip()
        if key == f"{target[0]}.{target[1]}":
            raise ParameterError(
                f"--opt {item!r} conflicts with the sweep over {parameter}, which sets it at every point"
            )


def _run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before anything runs or downloads
    formats_of(args)
    check_parallel(args)
    decision_budget(args)
    sweep = build_spec(args)
    runs = parse_runs(list(sweep.strategies), args.opt)
    check_presets(args)
    check_opt_conflict(sweep.parameter, [e.name for e in runs], args.opt)
    points = expand(sweep.parameter, sweep.values, [e.name for e in runs])
    given = parse_param_overrides(args.param)
    for point in points:
        point.refuse_overrides(given)
    check_out_name(
        args.out, inner=[max((p.label for p in points), key=len), "runs", max((e.name for e in runs), key=len)]
    )
    check_new_folder(args.out)  # before a first run's data download
    spec = run_spec(args, scenario_request(args), runs=runs)
    for point in points:  # a run option's values and a --param set by the sweep too are refused before any run
        point.spec_of(spec, spec.request)
    note(f"sweep {sweep.name}: {len(points)} points x {', '.join(spec.names)} on {spec.request.name}")
    outcome = run_sweep(
        sweep,
        points,
        spec,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=progress_of(args),
    )
    folder, table = outcome.folder, outcome.table
    unproven = note_outcome(outcome)
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "sweep": sweep.name,
                "parameter": sweep.parameter,
                "rows": table.to_dict(orient="records"),
                "unproven": unproven,
            }
        )
        return 0
    sel = table[table["kpi"].isin(sweep.kpis) & table["run"].isin(spec.names)]
    wide = sel.pivot_table(index="point", columns=["kpi", "run"], values="value")
    print(wide.round(3).to_string())
    print(f"\nresults written to {folder}  (report: {folder / 'report.md'}; in a browser: {folder / REPORT_HTML})")
    return 0
