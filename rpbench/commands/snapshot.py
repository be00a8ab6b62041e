"""``rpbench snapshot``: freeze chosen rounds' models of simulation runs into instance files."""

from __future__ import annotations

import argparse

from rpbench.bench.snapshot import take_snapshots
from rpbench.commands._common import add_scenario_args, note, print_json, scenario_request
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import parse_run_options, parse_strategies
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.results.store import check_new_folder


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "snapshot",
        help="freeze per-round models into instance files",
        description="Simulate strategies and save the models of chosen rounds as instance files "
        "(format: instances/README.md) for `rpbench bench`.",
    )
    add_scenario_args(p)
    p.add_argument("--strategies", default="mb,rtv,fl", help="strategies to snapshot (default mb,rtv,fl)")
    p.add_argument("--solver", default="highs", help="solver preset used during the runs")
    p.add_argument("--rounds", default=None, help="round indices to freeze, e.g. 10,100,200 (default: largest)")
    p.add_argument("--largest", type=int, default=3, help="without --rounds: freeze the N largest rounds")
    p.add_argument("--opt", action="append", default=[], metavar="STRATEGY.KEY=VALUE", help="strategy option")
    p.add_argument("--out", required=True, help="folder to create for the instance files")
    p.add_argument("--json", action="store_true", help="print the manifest as JSON")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    strategies = [s for s in parse_strategies(args.strategies) if s not in ORACLE_RUNS]
    run_options = parse_run_options(args.opt, strategies)
    rounds = None
    if args.rounds:
        try:
            rounds = sorted({int(r) for r in args.rounds.split(",") if r.strip()})
        except ValueError:
            raise ParameterError(f"--rounds {args.rounds!r}: expected round indices like 10,100,200") from None
    if args.largest < 1:
        raise ParameterError(f"--largest {args.largest} must be >= 1")
    check_new_folder(args.out)  # before simulating: a bad --out must not cost the runs
    scenario = scenario_request(args).build()
    note(scenario.label)
    folder, entries = take_snapshots(
        scenario, strategies, args.solver, args.out, rounds=rounds, largest=args.largest, run_options=run_options
    )
    if args.json:
        print_json({"folder": str(folder), "instances": entries})
        return 0
    for e in entries:
        size = e["size"]
        print(
            f"{e['file']:<40} {e['strategy']:<6} round {e['round']:>5}  {size['rows']:>5} rows "
            f"{size['cols']:>6} cols  objective {e['objective']:.0f}"
        )
    print(f"\n{len(entries)} instance(s) written to {folder}; solve them with: rpbench bench {folder}")
    return 0
