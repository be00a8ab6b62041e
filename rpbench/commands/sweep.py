"""``rpbench sweep``: parameter sweeps in the layout of the paper's Tables 3-6."""

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
from rpbench.harness.comparison import parse_run_options, parse_strategies
from rpbench.harness.strict import strict_mode
from rpbench.harness.sweep import SWEEPS, SweepSpec, expand, parse_over, run_sweep
from rpbench.paths import require_data_dir
from rpbench.results.store import check_new_folder
from rpbench.scenarios import scenario_spec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="parameter sweeps (the paper's Tables 3-6)",
        description="Run a parameter sweep: a predefined one of the paper "
        f"({', '.join(SWEEPS)}) or --over NAME=V1,V2,...; points run in parallel "
        "in local worker processes (or on an existing Dask cluster, --scheduler).",
    )
    p.add_argument("sweep", nargs="?", choices=list(SWEEPS), help="predefined sweep")
    p.add_argument("--over", default=None, metavar="NAME=V1,V2,...", help="sweep any parameter instead")
    p.add_argument("--values", default=None, help="override a predefined sweep's values, e.g. 60,90,120")
    p.add_argument("--strategies", default=None, help="strategies (default: the paper's for that table)")
    add_scenario_args(p)
    p.add_argument("--solver", default="highs", help="solver preset (default highs)")
    p.add_argument("--opt", action="append", default=[], metavar="STRATEGY.KEY=VALUE", help="strategy option")
    p.add_argument("--out", default=None, help="sweep folder to create")
    p.add_argument("--workers", type=int, default=None, help="parallel workers (default one per core)")
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="an existing Dask scheduler, e.g. tcp://host:8786 (needs the dask extra: pip install 'rpbench[dask]')",
    )
    p.add_argument("--json", action="store_true", help="print the sweep table as one JSON object")
    add_strict_arg(p)
    p.set_defaults(handler=run)


def build_spec(args: argparse.Namespace) -> SweepSpec:
    if (args.sweep is None) == (args.over is None):
        raise ParameterError(f"give either a predefined sweep ({', '.join(SWEEPS)}) or --over NAME=V1,V2,...")
    if args.over:
        parameter, values = parse_over(args.over)
        strategies = tuple(parse_strategies(args.strategies or "mb,rtv,fl"))
        return SweepSpec(
            name=parameter,
            parameter=parameter,
            values=tuple(values),
            strategies=strategies,
            kpis=("avg_detour_m", "total_saving_km", "avg_response_time_s", "response_rate", "pairing_ratio"),
        )
    spec = SWEEPS[args.sweep]
    values = tuple(parse_over(f"{spec.parameter}={args.values}")[1]) if args.values else spec.values
    strategies = tuple(parse_strategies(args.strategies)) if args.strategies else spec.strategies
    return SweepSpec(spec.name, spec.parameter, values, strategies, spec.kpis, spec.paper_table)


def run(args: argparse.Namespace) -> int:
    spec = build_spec(args)
    points = expand(spec.parameter, spec.values)
    run_options = parse_run_options(args.opt, list(spec.strategies))
    request = scenario_request(args)
    if request.data_dir is None and scenario_spec(request.name).needs_data:
        # workers resolve no default folder of their own: pass the one found here
        request = request.replace(data_dir=str(require_data_dir(None, what=f"scenario {request.name!r}")))
    check_new_folder(args.out)  # before simulating: a bad --out must not cost the whole sweep
    note(f"sweep {spec.name}: {len(points)} points x {', '.join(spec.strategies)} on {request.name}")
    with strict_mode(args.strict):  # the sweep's workers inherit it (rpbench.harness.parallel)
        folder = run_sweep(
            spec,
            points,
            request=request,
            preset=args.solver,
            run_options=run_options,
            out=args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            command=command_line(),
        )
    table = pd.read_csv(folder / "sweep.csv")
    unproven = note_unproven(folder)
    if args.json:
        print_json(
            {
                "results_dir": str(folder),
                "sweep": spec.name,
                "parameter": spec.parameter,
                "rows": table.to_dict(orient="records"),
                "unproven": unproven,
            }
        )
        return 0
    sel = table[table["kpi"].isin(spec.kpis) & table["run"].isin(spec.strategies)]
    wide = sel.pivot_table(index="point", columns=["kpi", "run"], values="value")
    print(wide.round(3).to_string())
    print(f"\nresults written to {folder}  (report: {folder / 'report.md'})")
    return 0
