"""``rpbench snapshot``: freeze chosen rounds' models of simulation runs into instance files."""

from __future__ import annotations

import argparse

from rpbench.bench.snapshot import take_snapshots
from rpbench.commands._common import add_scenario_args, note, print_json, scenario_request
from rpbench.commands._runs import parse_runs, run_spec
from rpbench.exceptions import ParameterError
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
    runs = [e for e in parse_runs(args.strategies, args.opt) if not e.offline]
    if not runs:
        raise ParameterError(
            f"--strategies {args.strategies!r}: offline runs have no rounds to freeze; name a strategy"
        )
    rounds = None
    if args.rounds:
        try:
            rounds = sorted({int(r) for r in args.rounds.split(",") if r.strip()})
        except ValueError:
            raise ParameterError(f"--rounds {args.rounds!r}: expected round indices like 10,100,200") from None
    if args.largest < 1:
        raise ParameterError(f"--largest {args.largest} must be >= 1")
    spec = run_spec(args, scenario_request(args), runs=runs)
    check_new_folder(args.out)  # before the scenario is built and simulated
    scenario = spec.request.build()
    note(scenario.label)
    folder, entries = take_snapshots(spec, args.out, scenario=scenario, rounds=rounds, largest=args.largest)
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
