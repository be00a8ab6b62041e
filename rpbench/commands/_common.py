"""Argument helpers shared by subcommands (data folder, scenario choice, output)."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from typing import Any

from rpbench.exceptions import ParameterError
from rpbench.results import to_jsonable
from rpbench.scenarios import ScenarioRequest, default_scenario_name
from rpbench.scenarios.base import Params


def add_data_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", metavar="DIR", default=None,
                        help="Haikou data folder (default: $RPBENCH_DATA, else ../shared/data/haikou, else the folder "
                             "`rpbench data fetch` fills; `rpbench list` says which)")


def add_scenario_args(parser: argparse.ArgumentParser, *, positional: bool = False) -> None:
    """--scenario/--date/--sample/--seed plus parameter overrides."""
    if positional:
        parser.add_argument("scenario", metavar="NAME", help="scenario name (see `rpbench list`)")
    else:
        parser.add_argument("--scenario", default=None,
                            help="scenario name (default: haikou-peak, or toy when no data folder exists)")
    parser.add_argument("--date", default=None, help="date YYYY-MM-DD (default 2017-05-01)")
    parser.add_argument("--sample", type=float, default=None,
                        help="fraction of orders kept, in (0, 1] (haikou-peak default 0.3)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--fleet-at", dest="fleet_placement", default="order_origins",
                        choices=("order_origins", "random_nodes"), help="initial vehicle positions")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a parameter, e.g. --param dt_s=30 (repeatable; see `rpbench list`)")
    add_data_arg(parser)


def parse_param_overrides(items: list[str]) -> dict[str, float]:
    out: dict[str, float] = {}
    known = set(Params().as_dict())
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in known:
            raise ParameterError(f"--param {item!r}: expected NAME=VALUE with NAME one of {', '.join(sorted(known))}")
        try:
            out[name] = float(value)
        except ValueError:
            raise ParameterError(f"--param {item!r}: value {value!r} is not a number") from None
    return out


def scenario_request(args: argparse.Namespace) -> ScenarioRequest:
    """The scenario the arguments name (without --scenario: haikou-peak, or the toy city without data)."""
    name = args.scenario or default_scenario_name(args.data)
    if args.scenario is None and name == "toy":
        note("no Haikou data folder found: running the built-in SYNTHETIC toy city (pass --data DIR for Haikou)")
    return ScenarioRequest(name=name, date=args.date, sample=args.sample, seed=args.seed,
                           params=tuple(parse_param_overrides(args.param).items()),
                           fleet_placement=args.fleet_placement, data_dir=args.data)


def command_line() -> str | None:
    """The command as typed (recorded in results folders)."""
    return "rpbench " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv else None


def print_json(obj: Any) -> None:
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def note(message: str) -> None:
    """A one-line remark for humans, on stderr (never pollutes --json output)."""
    print(message, file=sys.stderr)
