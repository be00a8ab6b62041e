"""Run an uninterruptible solver call in a forked child that is killed at a deadline.

Sparse blossom (PyMatching) and Blossom V (OGDF) have no time limit of their
own; a call with a deadline runs in a ``fork``-ed child, which inherits the
arrays (nothing is pickled in) and the libraries already loaded, and is
killed when the deadline passes.
"""

from __future__ import annotations

import time

import numpy as np

from rpbench.exceptions import SolverError


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
    child = ctx.Process(target=_child_main, args=(send, fn, args))
    child.start()
    send.close()
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
