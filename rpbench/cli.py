"""The ``rpbench`` command line.

Each subcommand lives in its own module under :mod:`rpbench.commands` and
exposes ``register(subparsers)``; the parser it adds carries a ``handler``
default.  Every :class:`~rpbench.exceptions.RpbenchError` becomes one line
on stderr and exit status 2, and so does an OSError no command caught
(naming the path); ``--json`` output is a single JSON object on stdout
(progress bars and notes go to stderr).  SIGTERM (a batch scheduler, a
container stop) raises :class:`Terminated` in the main thread, so every
cleanup of half-written results runs; then one line and exit status 143.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator

from rpbench.exceptions import RpbenchError, naming_out_as
from rpbench.version import __version__

#: Subcommand modules, in the order ``rpbench --help`` lists them.
COMMANDS = (
    "run",
    "check",
    "oracle",
    "predict",
    "snapshot",
    "bench",
    "sweep",
    "evaluate",
    "report",
    "publish",
    "scenario",
    "list",
    "data",
    "city",
    "replicate",
    "train",
    "instances",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rpbench",
        description="Benchmark suite for dynamic ride-pooling dispatch on real road networks "
        "(Haikou, Manhattan, any imported city).",
    )
    parser.add_argument("--version", action="version", version=f"rpbench {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"rpbench.commands.{name}").register(sub)
    return parser


#: Exit status after SIGTERM (the shell's 128 + signal number).
EXIT_TERMINATED = 128 + signal.SIGTERM


class Terminated(BaseException):
    """SIGTERM, raised in the main thread like KeyboardInterrupt for SIGINT.

    A BaseException, so no ``except Exception`` swallows it on its way up
    through the cleanups (``finally`` blocks, the results-folder context).
    """


def _raise_terminated(signum, frame) -> None:
    # Once is enough: a second SIGTERM must not interrupt the cleanup the first one started
    # (SIGKILL still stops a cleanup that hangs).
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise Terminated()


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Turn SIGTERM into :class:`Terminated` and SIGINT into KeyboardInterrupt for the body, whatever this
    process inherited (a shell starts a background job with SIGINT ignored, and Python then leaves it
    ignored: ``kill -INT`` would do nothing).  The previous handlers are restored afterwards, for callers
    that run :func:`main` in-process.  Only the main thread can install handlers."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)


def main(argv: list[str] | None = None) -> int:
    _escape_unencodable_output()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "handler", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        with sigterm_raises(), naming_out_as("--out"):
            return int(args.handler(args) or 0)
    except RpbenchError as exc:
        print(f"rpbench: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rpbench: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print("rpbench: terminated (SIGTERM); nothing half-written was left", file=sys.stderr)
        return EXIT_TERMINATED
    except BrokenPipeError:
        return 0
    except OSError as exc:  # a file-system error no command turned into an RpbenchError: still one line
        print(f"rpbench: error: {os_error_line(exc)}", file=sys.stderr)
        return 2


def entry() -> None:
    """The ``rpbench`` console script: :func:`main`, then, after a success, the process ends at once.

    Every file is written and closed, every child process reaped and the output flushed before
    :func:`main` returns, so what an ordinary interpreter exit adds is only the tearing down of the loaded
    libraries' objects (numba's and LLVM's among them): about a second after a run, for nothing.  Callers
    that run :func:`main` in-process keep their interpreter.
    """
    code = main()
    if code != 0:
        # An error or a stop: an ordinary exit, whose second matters nothing here.  It lets multiprocessing
        # release the semaphores of a pool stopped mid-task; skipped, the pool's resource tracker warns about
        # "leaked" ones on stderr after rpbench's last line.
        sys.exit(code)
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # a closed pipe (``rpbench list | head``) or stream
            stream.flush()
    os._exit(code)


def _escape_unencodable_output() -> None:
    """Print what the terminal's encoding cannot carry (a non-UTF-8 path's bytes, under a strict locale) as
    escapes, never as a UnicodeEncodeError after the work is done."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)  # a test's capture stream may not have it
        if reconfigure is not None:
            with contextlib.suppress(ValueError, OSError):  # a detached or closed stream: leave it
                reconfigure(errors="backslashreplace")


def os_error_line(exc: OSError) -> str:
    """``[Errno 13] Permission denied: '/x'`` as ``'/x': permission denied`` (one line, path first)."""
    what = (exc.strerror or str(exc) or type(exc).__name__).strip()
    paths = [p for p in (exc.filename, exc.filename2) if p is not None]
    text = f"{' -> '.join(repr(str(p)) for p in paths)}: {what[:1].lower()}{what[1:]}" if paths else what
    return " ".join(text.split())


if __name__ == "__main__":  # pragma: no cover
    entry()
