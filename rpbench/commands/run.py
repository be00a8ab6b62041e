"""``rpbench run``: simulate strategies on a scenario, print the comparison, write a results folder."""

from __future__ import annotations

import argparse
import shlex
import sys

from ..exceptions import ParameterError
from ..harness import parse_strategies, run_comparison
from ..report import text_table
from ..scenarios import build_scenario, default_scenario_name
from ._common import add_scenario_args, note, print_json, scenario_kwargs

DEFAULT_STRATEGIES = "np,mb,rtv,fl-nd,fl,oracle1,oracle2,oracle1-enroute"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="simulate strategies and compare them (the paper's Table 2)",
                       description="Simulate dispatching strategies on a scenario, print the comparison table "
                                   "(strategies as columns) and write a new results folder.")
    add_scenario_args(p)
    p.add_argument("--strategies", default=DEFAULT_STRATEGIES,
                   help=f"comma-separated strategies and oracles (default {DEFAULT_STRATEGIES})")
    p.add_argument("--solver", default="highs", help="solver preset, solvers/NAME.toml (default highs)")
    p.add_argument("--oracle-solver", default=None, metavar="PRESET",
                   help="preset for Oracle-1/Oracle-2 (default: --solver; `matching` is the fastest exact one)")
    p.add_argument("--opt", action="append", default=[], metavar="STRATEGY.KEY=VALUE",
                   help="strategy option, e.g. --opt rtv.c_ko=large (repeatable)")
    p.add_argument("--out", default=None, help="results folder to create (default ./rpbench-runs/<stamp>_...)")
    p.add_argument("--json", action="store_true", help="print the KPI table as one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--dates", default=None, metavar="A..B|A,B,...",
                   help="run the peak hour of several days (haikou-peak), e.g. 2017-05-01..2017-05-14")
    p.add_argument("--workers", type=int, default=None, help="parallel worker processes for --dates "
                   "(default: one per core; 1 = in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run --dates on an existing Dask cluster (e.g. tcp://host:8786) instead of a local one")
    p.set_defaults(handler=run)


def parse_options(items: list[str], strategies: list[str]) -> dict[str, dict]:
    out: dict[str, dict] = {}
    for item in items:
        key, sep, value = item.partition("=")
        name, dot, option = key.partition(".")
        if not sep or not dot or not option:
            raise ParameterError(f"--opt {item!r}: expected STRATEGY.KEY=VALUE, e.g. rtv.c_ko=large")
        if name not in strategies:
            raise ParameterError(f"--opt {item!r}: strategy {name!r} is not in --strategies")
        out.setdefault(name, {})[option] = _value(value)
    return out


def _value(text: str):
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    if low in ("none", "null"):
        return None
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def run(args: argparse.Namespace) -> int:
    strategies = parse_strategies(args.strategies)
    options = parse_options(args.opt, strategies)
    command = "rpbench " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv else None
    if args.dates:
        return run_many_days(args, strategies, options, command)
    name = args.scenario or default_scenario_name(args.data)
    if args.scenario is None and name == "toy":
        note("no Haikou data folder found: running the built-in synthetic toy city (pass --data DIR for Haikou)")
    kwargs = scenario_kwargs(args)
    scenario = build_scenario(name, **kwargs)
    note(scenario.label)
    scenario_args = {"date": args.date, "sample": args.sample, "seed": args.seed, "params": kwargs["param_overrides"],
                     "fleet_placement": args.fleet_placement}
    folder, table = run_comparison(scenario, strategies, args.solver, out=args.out, strategy_options=options,
                                   progress=False if args.no_progress else None, scenario_args=scenario_args,
                                   command=command, oracle_solver=args.oracle_solver)
    if args.json:
        print_json({"results_dir": str(folder), "scenario": scenario.label,
                    "kpis": {col: table[col].to_dict() for col in table.columns}})
        return 0
    print(text_table(table, title=f"{scenario.label} — solver preset {args.solver}"))
    print(f"\nresults written to {folder}  (verify: rpbench check {folder})")
    return 0


def run_many_days(args: argparse.Namespace, strategies: list[str], options: dict, command: str | None) -> int:
    from ..multiday import parse_dates, run_days
    from ..paths import require_data_dir
    from ..report import load_kpis
    if args.scenario not in (None, "haikou-peak") or args.date:
        raise ParameterError("--dates runs the haikou-peak scenario; drop --scenario/--date")
    kwargs = scenario_kwargs(args)
    dates = parse_dates(args.dates, require_data_dir(args.data, what="--dates"))
    note(f"running {len(dates)} peak hours ({dates[0]} .. {dates[-1]}) x {', '.join(strategies)}")
    folder = run_days(dates, data_dir=args.data, sample=args.sample, seed=args.seed,
                      param_overrides=kwargs["param_overrides"], fleet_placement=args.fleet_placement,
                      strategies=strategies, preset=args.solver, strategy_options=options, out=args.out,
                      workers=args.workers, scheduler=args.scheduler, command=command,
                      oracle_solver=args.oracle_solver)
    import pandas as pd
    summary = pd.read_csv(folder / "summary.csv")
    mean = summary.pivot(index="kpi", columns="run", values="mean")[[s for s in strategies]]
    if args.json:
        print_json({"results_dir": str(folder), "dates": dates,
                    "mean_kpis": {col: mean[col].to_dict() for col in mean.columns},
                    "per_day": {d: {c: t[c].to_dict() for c in t.columns}
                                for d in dates for t in [load_kpis(folder / d)]}})
        return 0
    print(text_table(mean, title=f"Mean over {len(dates)} peak hours ({dates[0]} .. {dates[-1]}), "
                                 f"solver preset {args.solver}"))
    print(f"\nresults written to {folder}  (per-day folders inside; report: {folder / 'report.md'})")
    return 0
