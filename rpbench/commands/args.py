"""Argument groups shared by subcommands: numbers with their ranges, the scenario, the data folder,
parallel workers, the strict policy and the decision budget.

Every numeric option is declared with :func:`add_number_arg` and its sane
:class:`~rpbench.options.Range`; the command's handler calls
:func:`check_numbers` first, so a value out of range is one line (not
argparse's usage block) before anything runs or downloads.
"""

from __future__ import annotations

import argparse
import shlex
from dataclasses import dataclass
from typing import Any

from rpbench.backends.presets import MAX_TIME_LIMIT_S
from rpbench.data.first_run import ensure_data_dir
from rpbench.exceptions import ParameterError
from rpbench.options import Range
from rpbench.scenarios import SCENARIOS, ScenarioRequest, default_scenario_name, scenario_spec
from rpbench.scenarios.base import Params
from rpbench.scenarios.common import MAX_DEMAND_MULTIPLIER
from rpbench.spec import MAX_DECISION_BUDGET_S

# ---------------------------------------------------------------- numbers
#: Sane ranges shared by several commands.  A seed is numpy's classic 32-bit range; a solve's time limit
#: is the presets' own bound (solvers/*.toml); a round's decision budget beyond a day flags nothing.
SEED = Range(0, 2**32 - 1, integer=True)


WORKERS = Range(1, 1024, integer=True)


@dataclass(frozen=True)
class SampleRange(Range):
    """``--sample``: a fraction of the orders, or above 1 a demand multiplier, which only a scenario that
    generates its orders takes (the scenario checks: ``ScenarioSpec.check_sample``)."""

    def describe(self) -> str:
        return f"0 < value <= 1, or a demand multiplier up to {self.high:g} for the synthetic {multiplier_scenarios()}"


def multiplier_scenarios() -> str:
    """The scenarios that take ``--sample`` above 1 (those that generate their orders and say so)."""
    return ", ".join(name for name, spec in SCENARIOS.items() if spec.max_sample > 1)


SAMPLE = SampleRange(0.0, MAX_DEMAND_MULTIPLIER, low_open=True)


TIME_LIMIT = Range(0.0, MAX_TIME_LIMIT_S, "s", low_open=True)


DECISION_BUDGET = Range(0.0, MAX_DECISION_BUDGET_S, "s", low_open=True)


class GivenOnce(argparse.Action):
    """An option that may be given once: a second one is an error, not a silent replacement of the first."""

    def __call__(self, parser, namespace, values, option_string=None):
        if getattr(namespace, self.dest, None) is not None:
            parser.error(f"{option_string} given twice; give it once")
        setattr(namespace, self.dest, values)


def add_number_arg(
    parser: argparse.ArgumentParser,
    flag: str,
    bounds: Range,
    *,
    help: str,
    default: float | None = None,
    metavar: str | None = None,
    dest: str | None = None,
) -> None:
    """A numeric option kept as typed, converted and range-checked by :func:`check_numbers`; its help says
    the range."""
    extra: dict[str, Any] = {"dest": dest} if dest else {}
    action = parser.add_argument(flag, default=default, metavar=metavar, help=f"{help}; {bounds.describe()}", **extra)
    numbers = dict(parser.get_default("numbers_") or {})
    numbers[action.dest] = (flag, bounds)
    parser.set_defaults(numbers_=numbers)


def check_numbers(args: argparse.Namespace) -> None:
    """Every numeric option given on the command line converted in place, or one error line naming the
    first one out of its range (``--time-limit 1e300 is out of range (0 < value <= 1e+06 s)``)."""
    for dest, (flag, bounds) in (getattr(args, "numbers_", None) or {}).items():
        value = getattr(args, dest)
        if isinstance(value, str):
            setattr(args, dest, bounds.check(flag, value, shlex.quote(value)))


def add_data_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        metavar="DIR",
        default=None,
        help="Haikou data folder (default: $RPBENCH_DATA, else ../shared/data/haikou, else the folder "
        "`rpbench data fetch` fills, fetched on first use; `rpbench list` says which)",
    )


def add_parallel_args(parser: argparse.ArgumentParser) -> None:
    """``--workers`` and ``--scheduler``: where the comparisons of a sweep or an evaluation run."""
    add_number_arg(parser, "--workers", WORKERS, help="parallel workers (default one per core)")
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="an existing Dask scheduler, e.g. tcp://host:8786 (needs the dask extra: pip install 'rpbench[dask]')",
    )


def add_offline_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--offline",
        action="store_true",
        help="never download: without a data folder, run the toy city (or fail when a Haikou scenario is "
        "named) instead of fetching the data first",
    )


def add_scenario_args(parser: argparse.ArgumentParser, *, positional: bool = False, one_draw: bool = True) -> None:
    """--scenario/--date/--sample/--seed plus parameter overrides (``one_draw=False``: without --date and
    --seed, for a command that gives its own lists of them)."""
    if positional:
        parser.add_argument("scenario", metavar="NAME", help="scenario name (see `rpbench list`)")
    else:
        parser.add_argument(
            "--scenario",
            default=None,
            help="scenario name (default: haikou-peak, fetching its data on first use; the toy city, "
            "said loudly, when that fails)",
        )
    if one_draw:
        parser.add_argument("--date", default=None, help="date YYYY-MM-DD (default 2017-05-01)")
    add_number_arg(
        parser,
        "--sample",
        SAMPLE,
        help="fraction of the orders kept (haikou-peak default 0.3); k > 1: k times the volume drawn anew "
        "from the same rates, the fleet scaled alike (a stress test; scenarios of real orders refuse it)",
    )
    if one_draw:
        add_number_arg(parser, "--seed", SEED, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--city",
        default=None,
        metavar="NAME",
        help="the city of scenario city: one imported with `rpbench city import NAME`, or a city folder",
    )
    parser.add_argument(
        "--window",
        default=None,
        metavar="HH:MM-HH:MM",
        help="the time window of a city's day (scenarios city, manhattan-peak, manhattan-day; default: "
        "the scenario's, e.g. 08:00-09:00)",
    )
    parser.add_argument(
        "--fleet-at",
        dest="fleet_placement",
        default="order_origins",
        choices=("order_origins", "random_nodes"),
        help="initial vehicle positions",
    )
    parser.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter, e.g. --param dt_s=30 (repeatable; see `rpbench list`)",
    )
    add_data_arg(parser)
    add_offline_arg(parser)


def parse_param_overrides(items: list[str]) -> dict[str, float]:
    """``--param NAME=VALUE`` items, each name given once and every value within its sane range
    (:class:`~rpbench.scenarios.base.Params`), checked before any download or build."""
    out: dict[str, float] = {}
    known = set(Params().as_dict())
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in known:
            raise ParameterError(f"--param {item!r}: expected NAME=VALUE with NAME one of {', '.join(sorted(known))}")
        if name in out:
            raise ParameterError(f"--param {name} is given twice; give it once")
        try:
            out[name] = float(value)
        except ValueError:
            raise ParameterError(f"--param {item!r}: value {value!r} is not a number") from None
    Params().replace(**out)
    return out


def progress_of(args: argparse.Namespace) -> bool | None:
    """``--no-progress`` as the harness takes it: False to hide the bars, None to show them on a terminal."""
    return False if getattr(args, "no_progress", False) else None


def scenario_request(args: argparse.Namespace) -> ScenarioRequest:
    """The scenario the arguments name, its data folder fetched first when it needs one and none is found
    (:mod:`rpbench.data.first_run`; not with ``--offline``).  Without ``--scenario``: haikou-peak, or the
    toy city after a banner when its data cannot be had; a named scenario is never swapped."""
    check_numbers(args)  # idempotent: a command that forgot still fails before any download
    params = tuple(parse_param_overrides(args.param).items())  # a bad --param fails before any download
    offline = bool(getattr(args, "offline", False))
    progress = progress_of(args)
    if args.scenario is None:
        name = default_scenario_name(args.data, offline=offline, progress=progress)
    else:
        name = args.scenario
        spec = scenario_spec(name)
        if args.sample is not None:
            spec.check_sample(args.sample)  # --sample 4 of real orders: one line before any download
        if spec.needs_data:
            ensure_data_dir(args.data, what=f"scenario {name!r}", offline=offline, progress=progress, city=spec.city)
    return ScenarioRequest(
        name=name,
        date=getattr(args, "date", None),
        sample=args.sample,
        seed=getattr(args, "seed", 0),
        params=params,
        fleet_placement=args.fleet_placement,
        data_dir=args.data,
        city=getattr(args, "city", None),
        window=getattr(args, "window", None),
    )


# ------------------------------------------------------------ unproven solves
def add_strict_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--strict",
        action="store_true",
        help="fail (exit 2, nothing written) when the solver stops any round or oracle before "
        "proving optimality (time limit, gap) instead of noting and marking it",
    )


# ---------------------------------------------------------- decision budget
def add_decision_budget_arg(parser: argparse.ArgumentParser) -> None:
    add_number_arg(
        parser,
        "--decision-budget",
        DECISION_BUDGET,
        metavar="SECONDS",
        help="flag the rounds whose decision (strategy build plus solver build, solve and decoding) takes longer "
        "than SECONDS: the KPI rounds_over_budget, an over_budget column in rounds.csv.gz and a note per run; "
        "the simulation is unchanged (default: no budget)",
    )


def decision_budget(args: argparse.Namespace) -> float | None:
    """``--decision-budget`` as seconds (None without it); a value out of its range is one error line."""
    value = getattr(args, "decision_budget", None)
    if value is None:
        return None
    text = value if isinstance(value, str) else repr(value)
    return float(DECISION_BUDGET.check("--decision-budget", value, shlex.quote(text)))
