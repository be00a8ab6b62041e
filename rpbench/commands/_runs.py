"""Command-line text -> :class:`~rpbench.spec.RunSpec`: the run arguments shared by run, sweep and snapshot.

``--strategies a,b,...`` names the runs (:func:`~rpbench.spec.resolve_runs`
resolves them), ``--opt RUN.OPTION=VALUE`` sets a run's option (RUN is the
run's name, or the source it was given by), ``--solver`` / ``--oracle-solver``
name the presets, ``--strict`` the policy for unproven solves and ``--decision-budget`` the time a round's
decision may take before it is flagged.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Sequence

from rpbench.backends.presets import load_preset
from rpbench.commands._figures import formats_of
from rpbench.commands.args import add_decision_budget_arg, add_strict_arg, decision_budget
from rpbench.commands.output import command_line
from rpbench.exceptions import ParameterError
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunEntry, RunSpec, resolve_runs, typed_options

#: What ``rpbench run`` compares without ``--strategies``.
DEFAULT_STRATEGIES = "np,mb,rtv,fl-nd,fl,fl-perfect,hindsight,bound,oracle1,oracle2"


def add_run_args(parser: argparse.ArgumentParser, *, strategies: str | None = DEFAULT_STRATEGIES) -> None:
    """``--strategies``, ``--solver``, ``--oracle-solver``, ``--opt``, ``--strict`` and ``--decision-budget``."""
    default = f" (default {strategies})" if strategies else ""
    parser.add_argument(
        "--strategies",
        default=strategies,
        help=f"comma-separated strategies and offline runs{default}; a plug-in by entry-point name or MODULE:CLASS; "
        "a variant of a strategy as NAME@OPTION=VALUE (e.g. fl@tau0_s=200), a run of its own",
    )
    parser.add_argument("--solver", default="highs", help="solver preset, solvers/NAME.toml (default highs)")
    parser.add_argument(
        "--oracle-solver",
        default=None,
        metavar="PRESET",
        help="preset for the offline runs (default: --solver; `matching` is the fastest exact one)",
    )
    parser.add_argument(
        "--opt",
        action="append",
        default=[],
        metavar="RUN.KEY=VALUE",
        help="a run's option, e.g. --opt rtv.c_ko=large (repeatable; `rpbench list` names them)",
    )
    add_strict_arg(parser)
    add_decision_budget_arg(parser)


def split_list(text: str) -> list[str]:
    """``a, b,c`` -> ``["a", "b", "c"]`` (empty items dropped)."""
    return [s.strip() for s in text.split(",") if s.strip()]


def parse_opt_items(items: Sequence[str], entries: Sequence[RunEntry]) -> list[RunEntry]:
    """``entries`` with the ``--opt RUN.NAME=VALUE`` items applied, each run's options typed and checked.

    RUN is the longest run name or source of ``entries`` that the key starts
    with, followed by a dot: names and ``module:Class`` sources may contain
    dots themselves (``--opt mypkg.rules:Greedy.threshold=3``).
    """
    # a variant (``fl@tau0_s=200``) is reached by its name only: its source is its strategy's
    by_prefix = {e.source: e.name for e in entries if not e.settings} | {e.name: e.name for e in entries}
    raw: dict[str, dict[str, str]] = {e.name: dict(e.settings) for e in entries}
    for item in items:
        named = next((p for p in sorted(by_prefix, key=len, reverse=True) if item.startswith(f"{p}.")), None)
        if named is not None:  # a variant's name holds '=' itself: split after the run name
            prefix, (option, sep, value) = named, item[len(named) + 1 :].partition("=")
        else:
            key, sep, value = item.partition("=")
            prefix, option = split_option_key(key, list(by_prefix))
        if not sep or not prefix or not option.strip():
            raise ParameterError(f"--opt {item!r}: expected RUN.KEY=VALUE, e.g. rtv.c_ko=large")
        if prefix not in by_prefix:
            raise ParameterError(f"--opt {item!r}: run {prefix!r} is not in --strategies ({', '.join(raw)})")
        raw[by_prefix[prefix]][option.strip()] = value
    return [dataclasses.replace(e, options=typed_options(e, raw[e.name])) for e in entries]


def split_option_key(key: str, prefixes: Sequence[str]) -> tuple[str, str]:
    """``RUN.OPTION`` -> (RUN, OPTION): the longest of ``prefixes`` followed by a dot, else a best guess for
    the error message (up to the first dot; after the colon for a ``module:Class`` source); OPTION is ``""``
    when there is no dot."""
    for prefix in sorted(prefixes, key=len, reverse=True):
        if key.startswith(f"{prefix}."):
            return prefix, key[len(prefix) + 1 :]
    colon = key.find(":")
    dot = key.find(".", colon + 1 if colon >= 0 else 0)
    return (key, "") if dot < 0 else (key[:dot], key[dot + 1 :])


def parse_runs(strategies: str | Sequence[str], opts: Sequence[str] = ()) -> list[RunEntry]:
    """``--strategies`` text (or names) and ``--opt`` items -> typed run entries, in order."""
    names = split_list(strategies) if isinstance(strategies, str) else list(strategies)
    return parse_opt_items(opts, resolve_runs(names))


def check_presets(args: argparse.Namespace) -> None:
    """``--solver`` and ``--oracle-solver`` loaded (and so checked) before the scenario is fetched or built."""
    load_preset(args.solver)
    if getattr(args, "oracle_solver", None):
        load_preset(args.oracle_solver)


def run_spec(args: argparse.Namespace, request: ScenarioRequest, *, runs: Sequence[RunEntry] | None = None) -> RunSpec:
    """The run specification of a command's arguments (``runs``: already parsed entries)."""
    entries = list(runs) if runs is not None else parse_runs(args.strategies, args.opt)
    return RunSpec(
        request=request,
        runs=tuple(entries),
        preset=args.solver,
        oracle_preset=getattr(args, "oracle_solver", None),
        strict=bool(getattr(args, "strict", False)),
        command=command_line(),
        decision_budget_s=decision_budget(args),
        formats=formats_of(args),
    )
