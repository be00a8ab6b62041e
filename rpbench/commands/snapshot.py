"""``rpbench snapshot``: freeze chosen rounds' models of simulation runs into instance files."""

from __future__ import annotations

import argparse

from rpbench.bench.snapshot import take_snapshots
from rpbench.commands._runs import check_presets, parse_runs, run_spec
from rpbench.commands.args import add_number_arg, add_scenario_args, check_numbers, scenario_request
from rpbench.commands.checks import check_out_name, check_unique
from rpbench.commands.output import note, print_json
from rpbench.exceptions import ParameterError
from rpbench.options import Range
from rpbench.results.store import check_new_folder

#: A round index: a day of 0.1 s rounds (Δt's lower bound) has 864,000.
ROUND = Range(0, 864_000, integer=True)
LARGEST = Range(1, 10_000, integer=True)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "snapshot",
        help="freeze per-round models into instance files",
        description="Simulate strategies and save the models of chosen rounds as instance files "
        "(format: instances/README.md) for `rpbench bench`.",
    )
    add_scenario_args(p)
    p.add_argument(
        "--strategies",
        default="mb,rtv,fl",
        help="strategies to snapshot (default mb,rtv,fl); offline runs (bound, oracle1, oracle2) freeze their "
        "pairing model over all orders",
    )
    p.add_argument("--solver", default="highs", help="solver preset used during the runs")
    p.add_argument("--rounds", default=None, help="round indices to freeze, e.g. 10,100,200 (default: largest)")
    add_number_arg(p, "--largest", LARGEST, help="without --rounds: freeze the N largest rounds (default 3)")
    p.add_argument("--opt", action="append", default=[], metavar="STRATEGY.KEY=VALUE", help="strategy option")
    p.add_argument("--out", required=True, help="folder to create for the instance files")
    p.add_argument("--json", action="store_true", help="print the manifest as JSON")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before anything runs or downloads
    runs = parse_runs(args.strategies, args.opt)
    check_presets(args)
    rounds = None
    if args.rounds is not None:
        items = [r.strip() for r in args.rounds.split(",") if r.strip()]
        if not items or not all(r.lstrip("-").isdigit() for r in items):
            raise ParameterError(f"--rounds {args.rounds!r}: expected round indices like 10,100,200")
        rounds = [ROUND.check(f"--rounds {args.rounds!r}: round", r, r) for r in items]
        check_unique(f"--rounds {args.rounds!r}", [str(r) for r in rounds])
        if args.largest is not None:
            raise ParameterError("--largest picks rounds without --rounds; give one of them")
        if all(e.offline for e in runs):
            raise ParameterError(
                f"--rounds: --strategies {args.strategies!r} names only offline runs, which have no rounds"
            )
    longest = max((e.name for e in runs), key=len)
    check_out_name(args.out, inner=[f"{args.scenario or 'haikou-peak'}_{longest}_round00000.npz"])
    check_new_folder(args.out)  # before the data is fetched, the scenario built and simulated
    spec = run_spec(args, scenario_request(args), runs=runs)
    scenario = spec.request.build()
    note(scenario.label)
    largest = 3 if args.largest is None else args.largest
    folder, entries = take_snapshots(spec, args.out, scenario=scenario, rounds=rounds, largest=largest)
    if args.json:
        print_json({"folder": str(folder), "instances": entries})
        return 0
    for e in entries:
        size = e["size"]
        where = f"round {e['round']:>5}" if "round" in e else "offline    "
        objective = "not solved" if e["objective"] is None else f"objective {e['objective']:.0f}"
        print(f"{e['file']:<40} {e['strategy']:<7} {where}  {size['rows']:>5} rows {size['cols']:>7} cols  {objective}")
    print(f"\n{len(entries)} instance(s) written to {folder}; solve them with: rpbench bench {folder}")
    return 0
