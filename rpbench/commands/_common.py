"""Argument helpers shared by subcommands (data folder, scenario choice, output)."""

from __future__ import annotations

import argparse
import json
import math
import os
import secrets
import shlex
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rpbench.data.first_run import ensure_data_dir
from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.results import run_folders, to_jsonable
from rpbench.results.report import over_budget_runs, unproven_runs
from rpbench.results.runs import run_label
from rpbench.scenarios import ScenarioRequest, default_scenario_name, scenario_spec
from rpbench.scenarios.base import Params


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
    parser.add_argument("--workers", type=int, default=None, help="parallel workers (default one per core)")
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


def add_scenario_args(parser: argparse.ArgumentParser, *, positional: bool = False) -> None:
    """--scenario/--date/--sample/--seed plus parameter overrides."""
    if positional:
        parser.add_argument("scenario", metavar="NAME", help="scenario name (see `rpbench list`)")
    else:
        parser.add_argument(
            "--scenario",
            default=None,
            help="scenario name (default: haikou-peak, fetching its data on first use; the toy city, "
            "said loudly, when that fails)",
        )
    parser.add_argument("--date", default=None, help="date YYYY-MM-DD (default 2017-05-01)")
    parser.add_argument(
        "--sample", type=float, default=None, help="fraction of orders kept, in (0, 1] (haikou-peak default 0.3)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
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
    """The scenario the arguments name, its data folder fetched first when it needs one and none is found
    (:mod:`rpbench.data.first_run`; not with ``--offline``).  Without ``--scenario``: haikou-peak, or the
    toy city after a banner when its data cannot be had; a named scenario is never swapped."""
    params = tuple(parse_param_overrides(args.param).items())  # a bad --param fails before any download
    offline = bool(getattr(args, "offline", False))
    progress = False if getattr(args, "no_progress", False) else None
    if args.scenario is None:
        name = default_scenario_name(args.data, offline=offline, progress=progress)
    else:
        name = args.scenario
        if scenario_spec(name).needs_data:
            ensure_data_dir(args.data, what=f"scenario {name!r}", offline=offline, progress=progress)
    return ScenarioRequest(
        name=name,
        date=args.date,
        sample=args.sample,
        seed=args.seed,
        params=params,
        fleet_placement=args.fleet_placement,
        data_dir=args.data,
    )


def command_line() -> str | None:
    """The command as typed (recorded in results folders)."""
    return "rpbench " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv else None


def print_json(obj: Any) -> None:
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def note(message: str) -> None:
    """A one-line remark for humans, on stderr (never pollutes --json output)."""
    print(message, file=sys.stderr)


# ------------------------------------------------------------ unproven solves
def add_strict_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--strict",
        action="store_true",
        help="fail (exit 2, nothing written) when the solver stops any round or oracle before "
        "proving optimality (time limit, gap) instead of noting and marking it",
    )


def note_unproven(folder: Path) -> dict[str, str]:
    """One note line per run of ``folder`` (and of each day / sweep point below it) that rests on solver
    answers not proven optimal; returns every such run with its first reason (to mark table columns)."""
    marked: dict[str, str] = {}
    for sub in run_folders(folder):
        where = "" if sub == folder else f"{sub.name}: "
        for run, why in unproven_runs(sub).items():
            note(
                f"rpbench: note: {where}{run_label(run)} {why}; its numbers are not proven optimal "
                "(--strict makes this an error)"
            )
            marked.setdefault(run, why)
    return marked


# ---------------------------------------------------------- decision budget
def add_decision_budget_arg(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--decision-budget",
        default=None,
        metavar="SECONDS",
        help="flag the rounds whose decision (strategy build plus solver build, solve and decoding) takes longer "
        "than SECONDS: the KPI rounds_over_budget, an over_budget column in rounds.csv.gz and a note per run; "
        "the simulation is unchanged (default: no budget)",
    )


def decision_budget(args: argparse.Namespace) -> float | None:
    """``--decision-budget`` as seconds (None without it); anything but a finite number > 0 is one error line
    (parsed here, not by argparse, whose error is a usage block)."""
    text = getattr(args, "decision_budget", None)
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"--decision-budget {text!r} must be a finite number of seconds > 0")
    return value


def note_over_budget(folder: Path) -> None:
    """One note line per run of ``folder`` (and of each day / sweep point / unit below it) with rounds slower
    than the folder's decision budget."""
    for sub in run_folders(folder):
        where = "" if sub == folder else f"{sub.name}: "
        for run, what in over_budget_runs(sub).items():
            note(f"rpbench: note: {where}{run}: {what}")


# ------------------------------------------------------------- output files
def check_out_file(path: str, option: str) -> Path:
    """Fail in one line, before any work, unless file ``path`` can be written: its folder exists and takes
    new files, and ``path`` is not a folder.  An existing file is replaced (atomically, see
    :func:`write_out_file`)."""
    out = Path(path)
    folder = out.parent
    if out.is_dir():
        raise ParameterError(f"{option} {path!r} is a folder; give a file name")
    if not folder.is_dir():
        state = "is not a folder" if os.path.lexists(folder) else "does not exist"
        raise ParameterError(f"{option} {path!r}: folder {str(folder)!r} {state}; create it or choose another path")
    try:  # try it: permission bits say nothing about root, read-only mounts or /proc
        fd, probe = tempfile.mkstemp(prefix=".rpbench-probe-", dir=folder)
    except OSError as exc:
        raise ParameterError(
            f"{option} {path!r}: cannot create files in {str(folder)!r} ({exc.strerror or exc})"
        ) from None
    os.close(fd)
    os.unlink(probe)
    return out


def write_out_file(path: Path, option: str, write: Callable[[Path], object]) -> None:
    """``write(tmp)`` a sibling temporary file, then rename it to ``path``: an interrupted or failed write
    leaves no half-written ``path`` (nor the temporary file); an OSError is one line naming ``path``."""
    # the random part makes the name unguessable (nothing to plant a link at); the original name last keeps
    # the suffix pandas picks compression by
    tmp = path.with_name(f".partial-{secrets.token_hex(6)}-{path.name}")
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and not isinstance(exc, RpbenchError):
            raise ParameterError(f"{option} {str(path)!r}: cannot write the file ({exc.strerror or exc})") from None
        raise
