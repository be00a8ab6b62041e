"""Run an uninterruptible solver call in a forked child that is killed at a deadline.

Sparse blossom (PyMatching) and Blossom V (OGDF) have no time limit of their
own; a call with a deadline runs in a ``fork``-ed child, which inherits the
arrays (nothing is pickled in) and the libraries already loaded, and is
killed when the deadline passes.  Every forked child of rpbench is started by
:func:`start_forked`, so that a stop signal arriving during the fork is not lost.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from rpbench.exceptions import SolverError

if TYPE_CHECKING:
    from multiprocessing.connection import Connection


class Timeout(Exception):
    """A solver call ran past its deadline (and its child was killed).

    A caller that has a feasible answer and a bound when the deadline strikes attaches them
    (``best``: chosen columns, ``bound``: on the objective) before passing the exception on.
    """

    def __init__(self) -> None:
        super().__init__()
        self.best: np.ndarray | None = None
        self.bound: int | None = None


def run_in_child(fn, args, deadline: float | None, *, solver: str):
    """``fn(*args)``, in a forked child killed at ``deadline`` (a ``time.perf_counter`` value).

    In-process when there is no deadline, or inside a daemonic process (a
    ``multiprocessing.Pool`` worker), which may not start children.  Raises
    :class:`Timeout` at the deadline and :class:`SolverError` naming
    ``solver`` if the child fails.
    """
    import multiprocessing

    if deadline is None or multiprocessing.current_process().daemon:
        return fn(*args)
    remaining = deadline - time.perf_counter()
    if remaining <= 0:
        raise Timeout()
    ctx = multiprocessing.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)
    child = start_piped(_child_main, (send, fn, args), receive, send)
    try:
        if not receive.poll(remaining):
            raise Timeout()
        ok, result = receive.recv()
    except EOFError:
        ok, result = False, f"the {solver} child process died"
    finally:
        if child.is_alive():
            child.kill()
        child.join()
        receive.close()
    if not ok:
        raise SolverError(f"{solver} failed: {result}")
    return result


def _child_main(conn, fn, args) -> None:
    try:
        conn.send((True, fn(*args)))
    except BaseException as exc:  # report, never hang the parent
        conn.send((False, f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


#: The stop signals (Ctrl-C, ``kill``) held back while a child is forked.
_HELD = (signal.SIGINT, signal.SIGTERM)


def start_forked(target: Callable[..., Any], args: tuple) -> Any:
    """A started ``fork``-ed :class:`multiprocessing.Process` running ``target(*args)``.

    SIGINT and SIGTERM are held back while it forks: Python runs its at-fork callbacks (logging's, among
    others) inside the fork, and an exception a signal handler raises there is printed and dropped, so a
    Ctrl-C or SIGTERM arriving then was lost and the run went on.  Held, the signal comes once the fork is
    done, in this process's own code; its exception then ends the child before it is raised here.

    The child leaves a stop to this process, which ends it: it ignores SIGINT (a terminal's Ctrl-C reaches
    the whole process group) and dies quietly of SIGTERM, then lets both through again and runs ``target``.
    """
    import multiprocessing

    child = multiprocessing.get_context("fork").Process(target=_released, args=(target, args))
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - no fork there either
        child.start()
        return child
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, _HELD)
    try:
        child.start()
    finally:
        try:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)  # a held signal's handler runs here
        except BaseException:
            if child.pid is not None:
                child.kill()
                child.join()
            raise
    return child


def start_piped(target: Callable[..., Any], args: tuple, mine: Connection, theirs: Connection) -> Any:
    """:func:`start_forked` for a child that talks over a pipe: this process's copy of the child's end
    ``theirs`` closed once it is forked, and ``mine`` too if it could not be."""
    try:
        return start_forked(target, args)
    except BaseException:
        mine.close()
        raise
    finally:
        theirs.close()


def _released(target: Callable[..., Any], args: tuple) -> None:
    """The forked child's start (:func:`start_forked`): its stop handling, the signals let through, ``target``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _HELD)
    target(*args)
