"""Argument helpers shared by subcommands (data folder, scenario choice, output).

Every numeric option is declared with :func:`add_number_arg` and its sane
:class:`~rpbench.options.Range`; the command's handler calls
:func:`check_numbers` first, so a value out of range is one line (not
argparse's usage block) before anything runs or downloads.
"""

from __future__ import annotations

import argparse
import datetime as dt
import importlib.util
import json
import os
import secrets
import shlex
import sys
import tempfile
import urllib.parse
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from rpbench.backends.presets import MAX_TIME_LIMIT_S
from rpbench.data.first_run import ensure_data_dir
from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.harness.spec import MAX_DECISION_BUDGET_S
from rpbench.options import Range
from rpbench.results import run_folders, to_jsonable
from rpbench.results.read import over_budget_runs, unproven_runs
from rpbench.results.runs import run_label
from rpbench.scenarios import ScenarioRequest, default_scenario_name, scenario_spec
from rpbench.scenarios.base import Params
from rpbench.scenarios.request import parse_date

# ---------------------------------------------------------------- numbers
#: Sane ranges shared by several commands.  A seed is numpy's classic 32-bit range; a solve's time limit
#: is the presets' own bound (solvers/*.toml); a round's decision budget beyond a day flags nothing.
SEED = Range(0, 2**32 - 1, integer=True)
WORKERS = Range(1, 1024, integer=True)
SAMPLE = Range(0.0, 1.0, low_open=True)
TIME_LIMIT = Range(0.0, MAX_TIME_LIMIT_S, "s", low_open=True)
DECISION_BUDGET = Range(0.0, MAX_DECISION_BUDGET_S, "s", low_open=True)


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


def check_unique(what: str, names: Iterable[str]) -> None:
    """One error line when ``names`` (dates, run names, sweep points) repeat one: the folders named after
    them would collide only when the results are written, after every simulation."""
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise ParameterError(f"{what} gives {name!r} twice; give each once")
        seen.add(name)


def check_date_list(option: str, text: str | None) -> None:
    """``--dates A,B,...``: each date well-formed and given once, checked before the data folder is needed
    (a range ``A..B`` cannot repeat a day)."""
    if text is None or ".." in text:
        return
    dates: list[dt.date] = [parse_date(d.strip()) for d in text.split(",") if d.strip()]
    check_unique(f"{option} {text!r}", (d.isoformat() for d in dates))


# ---------------------------------------------------------------- scheduler
#: Address schemes a Dask client connects to (``host:port`` alone means tcp).
DASK_SCHEMES = ("tcp", "tls", "ucx", "ws", "wss", "inproc")


def check_scheduler(address: str | None) -> None:
    """``--scheduler``: a Dask address (``tcp://host:8786``, ``host:8786``) with Dask installed, checked
    before any work (the client would otherwise fail with a traceback, or only after the set-up)."""
    if address is None:
        return
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    wrong = f"--scheduler {address!r} is not a Dask scheduler address (e.g. tcp://host:8786 or host:8786)"
    if scheme not in DASK_SCHEMES or not rest or any(c.isspace() for c in text):
        raise ParameterError(wrong)
    if scheme != "inproc":
        try:
            parts = urllib.parse.urlsplit(f"//{rest}")
            port = parts.port
        except ValueError:
            raise ParameterError(f"{wrong}: its port must be a number in [1, 65535]") from None
        if not parts.hostname or parts.path not in ("", "/") or parts.query or parts.fragment or port == 0:
            raise ParameterError(wrong)
    if importlib.util.find_spec("distributed") is None:
        raise ParameterError("--scheduler needs Dask, which is not installed: pip install 'rpbench[dask]'")


def check_parallel(args: argparse.Namespace) -> None:
    """``--workers`` and ``--scheduler``: their values, and not both (a cluster has its own workers)."""
    if getattr(args, "workers", None) is not None and getattr(args, "scheduler", None) is not None:
        raise ParameterError("--workers and --scheduler exclude each other: a Dask cluster has its own workers")
    check_scheduler(getattr(args, "scheduler", None))


# ---------------------------------------------------------------- out paths
#: What a results folder's staging name adds to its final name (``.NAME.partial-PID``, a PID of up to 7
#: digits: Linux's largest pid_max).
_STAGING_BYTES = len(".") + len(".partial-") + 7
#: Room for the deepest path rpbench writes below a results folder (``<day or point>/runs/<run>/<file>``):
#: day and file names are short, a run name is at most NAME_MAX bytes.
_INNER_BYTES = 64


def _limits(path: Path) -> tuple[int, int]:
    """NAME_MAX and PATH_MAX (bytes) of the file system holding ``path``'s nearest existing parent."""
    folder = path
    while not os.path.lexists(folder) and folder.parent != folder:
        folder = folder.parent
    try:
        return os.pathconf(folder, "PC_NAME_MAX"), os.pathconf(folder, "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):
        return 255, 4096


def check_out_name(out: str | None, option: str = "--out", *, inner: Sequence[str] = ()) -> None:
    """One error line when folder ``out`` or a file rpbench writes below it would have a name longer than
    the file system allows (NAME_MAX bytes a name, PATH_MAX a path): the write would fail only at the end,
    after every simulation.  ``inner`` are the names rpbench puts below ``out`` (days, points, runs)."""
    if out is None:
        return
    path = Path(os.path.abspath(out))
    name_max, path_max = _limits(path)
    for part in path.parts[1:]:
        if len(os.fsencode(part)) > name_max:
            raise ParameterError(
                f"{option}: the name {part[:40]!r}... is {len(os.fsencode(part))} bytes; the file system "
                f"allows {name_max}"
            )
    if len(os.fsencode(path.name)) + _STAGING_BYTES > name_max:
        raise ParameterError(
            f"{option}: the folder name {path.name[:40]!r}... is {len(os.fsencode(path.name))} bytes; at most "
            f"{name_max - _STAGING_BYTES} fit (the file system allows {name_max}, and rpbench writes the folder "
            "under a longer temporary name first)"
        )
    for name in inner:
        if len(os.fsencode(name)) > name_max:
            raise ParameterError(
                f"{option}: rpbench would write {name[:40]!r}... inside it, {len(os.fsencode(name))} bytes; the "
                f"file system allows {name_max}"
            )
    deepest = len(os.fsencode(str(path))) + _STAGING_BYTES + sum(len(os.fsencode(n)) + 1 for n in inner)
    if deepest + _INNER_BYTES > path_max:
        raise ParameterError(
            f"{option}: the path {str(path)[:40]!r}... is {len(os.fsencode(str(path)))} bytes; with the files "
            f"written inside it the paths would exceed the file system's {path_max}"
        )


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
    add_number_arg(parser, "--sample", SAMPLE, help="fraction of orders kept (haikou-peak default 0.3)")
    if one_draw:
        add_number_arg(parser, "--seed", SEED, default=0, help="random seed (default 0)")
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


def scenario_request(args: argparse.Namespace) -> ScenarioRequest:
    """The scenario the arguments name, its data folder fetched first when it needs one and none is found
    (:mod:`rpbench.data.first_run`; not with ``--offline``).  Without ``--scenario``: haikou-peak, or the
    toy city after a banner when its data cannot be had; a named scenario is never swapped."""
    check_numbers(args)  # idempotent: a command that forgot still fails before any download
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
        date=getattr(args, "date", None),
        sample=args.sample,
        seed=getattr(args, "seed", 0),
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
