"""``rpbench oracle``: solve Oracle-1 / Oracle-2 over all orders of a scenario (docs/algorithms.md §4)."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from rpbench.backends import load_preset
from rpbench.commands.args import (
    TIME_LIMIT,
    add_number_arg,
    add_scenario_args,
    add_strict_arg,
    check_numbers,
    scenario_request,
)
from rpbench.commands.checks import check_out_file, write_out_file
from rpbench.commands.output import note, print_json
from rpbench.exceptions import ParameterError
from rpbench.harness.strict import require_proven
from rpbench.options import Range
from rpbench.oracle.pairs import bound_rules
from rpbench.oracle.solve import (
    MAX_UNIT_M,
    MIN_UNIT_M,
    UNIT_M,
    PairRules,
    check_variant,
    find_candidates,
    solve_oracle,
)
from rpbench.report.comparison import UNPROVEN_MARK

UNIT_M_RANGE = Range(MIN_UNIT_M, MAX_UNIT_M, "m")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "oracle",
        help="solve the offline oracle (Oracle-1 max saving, Oracle-2 max pairs)",
        description="Solve the offline oracle over all orders of a scenario: Oracle-1 maximises "
        "the total distance saving, Oracle-2 the number of pairs (ties by saving). "
        "Pair feasibility follows docs/algorithms.md §4.2; the saving is counted once "
        "per pair.",
    )
    add_scenario_args(p)
    p.add_argument(
        "--variant",
        default="both",
        choices=("1", "2", "both", "bound"),
        help="which oracle (default both); bound: the proven upper bound on any strategy's saving (docs/bound.md)",
    )
    p.add_argument(
        "--solver",
        default="matching",
        metavar="PRESET",
        help="solver preset with an exact pairing backend (default matching)",
    )
    p.add_argument(
        "--both-pickup-orders",
        action="store_true",
        help="also allow the later order to be picked up first (oracle_both_pickup_orders)",
    )
    p.add_argument(
        "--pickup-check",
        action="store_true",
        help="require the pick-up distance to the second order <= R̄ (oracle_pickup_check)",
    )
    p.add_argument(
        "--allow-enroute",
        action="store_true",
        help="also pair an order requested while the first one rides (oracle_allow_enroute)",
    )
    add_number_arg(
        p,
        "--time-limit",
        TIME_LIMIT,
        metavar="S",
        help="override the preset's time limit in seconds (a stopped solve reports its gap)",
    )
    add_number_arg(
        p,
        "--unit-m",
        UNIT_M_RANGE,
        default=UNIT_M,
        metavar="M",
        help=f"resolution of the savings in the model, in metres (default {UNIT_M:g}). The solver proves the "
        "optimum of the savings rounded to M, which can miss the unrounded optimum by up to M per pair: the "
        "output states the proven bound ('rounding slack')",
    )
    p.add_argument("--pairs", metavar="CSV", default=None, help="write the chosen pairs to this CSV file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_strict_arg(p)
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before the scenario is built (or its data fetched)
    pairs_csv = check_out_file(args.pairs, "--pairs") if args.pairs else None  # before solving anything
    if args.variant == "bound" and (args.both_pickup_orders or args.pickup_check or args.allow_enroute):
        raise ParameterError("--variant bound takes no pair-rule flags: the bound's rules are fixed by its proof")
    preset = load_preset(args.solver)
    scenario = scenario_request(args).build()
    variants: tuple[int, ...]
    if args.variant == "bound":
        variants, rules = (1,), bound_rules(scenario.params)
    else:
        variants = (1, 2) if args.variant == "both" else (check_variant(args.variant),)
        rules = PairRules.from_params(
            scenario.params,
            both_pickup_orders=args.both_pickup_orders,
            pickup_check=args.pickup_check,
            allow_enroute=args.allow_enroute,
        )
    candidates = find_candidates(scenario.network.distances(), scenario.orders, rules)
    options = preset.options
    if args.time_limit is not None:
        options = dataclasses.replace(options, time_limit_s=args.time_limit)
    results = {
        v: solve_oracle(scenario, v, preset, candidates=candidates, options=options, unit_m=args.unit_m)
        for v in variants
    }
    for r in results.values():
        require_proven(f"{_name(r)} (solver preset {r.solver!r})", r.status.value, strict=args.strict)
        if r.status.value != "optimal":
            gap = r.kpis()["gap"]
            note(
                f"rpbench: note: {_name(r)} stopped with status {r.status.value} "
                f"(gap {'unknown' if math.isnan(gap) else f'{gap:.3g}'}); its value is not proven optimal "
                "(--strict makes this an error)"
            )
    if pairs_csv is not None:
        _write_pairs(pairs_csv, results)

    if args.json:
        print_json(
            {
                "scenario": scenario.name,
                "label": scenario.label,
                "rules": rules.as_dict(),
                "candidates": {
                    "evaluated": candidates.evaluated,
                    "feasible": len(candidates),
                    **candidates.stats,
                    "seconds": candidates.seconds,
                },
                **{
                    "bound" if r.is_upper_bound else f"oracle{v}": {
                        **r.kpis(),
                        "unit_m": r.model.unit_m,
                        "rounding_slack_m": r.rounding_slack_m,
                    }
                    for v, r in results.items()
                },
            }
        )
        return 0
    print(scenario.label)
    flags = [k for k in ("both_pickup_orders", "pickup_check", "allow_enroute") if getattr(rules, k)]
    if rules.window == "bound":
        print(
            f"  pair rules of the upper bound (docs/bound.md): t_B - t_A in [-K_B, K_A + (R̄ + l_A)/v], "
            f"D̄={rules.max_detour_m:g} m at A's origin, both pick-up orders, no R̄ test"
        )
    else:
        print(
            f"  pair rules: K̄={rules.planner_patience_s:g} s, D̄={rules.max_detour_m:g} m"
            + (f", R̄={rules.max_pickup_m:g} m" if rules.pickup_check else ", no R̄ test")
            + (f"; flags: {', '.join(flags)}" if flags else "; default flags (docs/algorithms.md A18)")
        )
    print(
        f"  candidates: {len(candidates):,} feasible of {candidates.evaluated:,} pairs in the time windows "
        f"({candidates.seconds:.3f} s)"
    )
    print(_table(results))
    for r in results.values():
        if not math.isnan(r.rounding_slack_m):
            print(
                f"  {_name(r)}: savings enter the model rounded to {r.model.unit_m:g} m; the unrounded optimum is "
                f"at most {r.rounding_slack_m:,.2f} m above its saving (proven rounding slack)"
            )
    return 0


_ROWS = (
    ("orders", "orders", "{:,.0f}"),
    ("pairs", "pairs", "{:,.0f}"),
    ("pooled_passengers", "pooled passengers", "{:,.0f}"),
    ("pairing_ratio", "pairing ratio", "{:.3f}"),
    ("avg_detour_m", "avg detour (m)", "{:,.0f}"),
    ("avg_shared_m", "avg shared (m)", "{:,.0f}"),
    ("total_saving_km", "total saving (km)", "{:,.1f}"),
    ("status", "status", "{}"),
    ("bound_m", "proven bound (m)", "{:,.0f}"),
    ("gap", "gap", "{:.2g}"),
    ("pairs_bound", "maximum pairs (proven)", "{:,.0f}"),
    ("edges", "model edges", "{:,.0f}"),
    ("model_s", "model build (s)", "{:.3f}"),
    ("build_s", "solver build (s)", "{:.3f}"),
    ("solve_s", "solve (s)", "{:.3f}"),
    ("total_s", "total incl. candidates (s)", "{:.3f}"),
)


def _table(results: dict) -> str:
    kpis = {v: r.kpis() for v, r in results.items()}
    unproven = [v for v, r in results.items() if r.status.value != "optimal"]
    header = ["metric"] + [
        f"{_name(results[v])} ({results[v].solver})" + (UNPROVEN_MARK if v in unproven else "") for v in results
    ]
    rows = [[label] + [_fmt(fmt, kpis[v][key]) for v in results] for key, label, fmt in _ROWS]
    widths = [max(len(r[c]) for r in [header] + rows) for c in range(len(header))]
    lines = ["  " + "  ".join(h.ljust(widths[0]) if c == 0 else h.rjust(widths[c]) for c, h in enumerate(header))]
    lines += [
        "  " + "  ".join(x.ljust(widths[0]) if c == 0 else x.rjust(widths[c]) for c, x in enumerate(r)) for r in rows
    ]
    if unproven:
        lines.append(f"  {UNPROVEN_MARK} not proven optimal: the solver stopped early (see its status and gap)")
    return "\n".join(lines)


def _name(result) -> str:
    return "Upper bound" if result.is_upper_bound else f"Oracle-{result.variant}"


def _fmt(fmt: str, value) -> str:
    if isinstance(value, float) and math.isnan(value):
        return "-"
    return fmt.format(value)


def _write_pairs(path: Path, results: dict) -> None:
    import pandas as pd

    table = pd.concat([r.pairs.assign(variant=v) for v, r in results.items()], ignore_index=True)
    write_out_file(path, "--pairs", lambda tmp: table.to_csv(tmp, index=False))
