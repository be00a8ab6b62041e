"""The ``rpbench`` command line.

Each subcommand lives in its own module under :mod:`rpbench.commands` and
exposes ``register(subparsers)``; the parser it adds carries a ``handler``
default.  Every :class:`~rpbench.exceptions.RpbenchError` becomes one line
on stderr and exit status 2; ``--json`` output is a single JSON object on
stdout (progress bars and notes go to stderr).
"""

from __future__ import annotations

import argparse
import importlib
import sys

from rpbench import __version__
from rpbench.exceptions import RpbenchError

#: Subcommand modules, in the order ``rpbench --help`` lists them.
COMMANDS = ("run", "check", "oracle", "predict", "snapshot", "bench", "sweep", "report", "publish", "scenario",
            "list", "data")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rpbench",
        description="Benchmark suite for dynamic ride-pooling dispatch on the Haikou road network.")
    parser.add_argument("--version", action="version", version=f"rpbench {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"rpbench.commands.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "handler", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.handler(args) or 0)
    except RpbenchError as exc:
        print(f"rpbench: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rpbench: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
