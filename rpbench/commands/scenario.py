"""``rpbench scenario NAME``: build a scenario and print its summary."""

from __future__ import annotations

import argparse
import time

from rpbench.commands.args import add_scenario_args, scenario_request
from rpbench.commands.output import print_json


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "scenario",
        help="build a scenario and print its summary",
        description="Build a scenario and print its summary (orders, vehicles, nodes, ...).",
    )
    add_scenario_args(p, positional=True)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    scenario = scenario_request(args).build()
    summary = scenario.summary()
    summary["build_s"] = round(time.perf_counter() - t0, 4)
    if args.json:
        print_json(summary)
        return 0
    params = summary.pop("params")
    print(summary.pop("label"))
    width = max(len(k) for k in summary)
    for key, value in summary.items():
        if isinstance(value, float):
            value = f"{value:,.1f}" if abs(value) >= 100 else f"{value:g}"
        print(f"  {key:<{width}}  {value}")
    print("  parameters: " + ", ".join(f"{k}={v:g}" for k, v in params.items()))
    return 0
