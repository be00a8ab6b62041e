"""A comparison's second process: the work that need not wait for the simulations, done on the other core.

A comparison's simulations run one after another on one core.  Parts of its other work do not depend on
them: the offline runs (bound, oracles) need only the scenario; a simulated run that needs nothing from
another run (no calibration, and no other run calibrated by it) needs only the scenario too; and report.md's
figures need only the written folder while report.html is rendered from the same files.  :func:`start` forks
a child when the comparison starts (nothing is pickled in: it inherits the scenario and the spec); the child
solves the offline runs and sends them back, then takes such independent runs from the end of the list
while the parent simulates from its start (:class:`Claims`: each run is simulated once, by whichever
process reaches it first), imports the plotting library, then waits until the parent has written the folder
and writes report.md and its figures into it while the parent writes report.html, one figure (``beside``)
drawn meanwhile by a child of its own.  The results are those of the serial path, the same functions on the
same inputs: the offline runs and the simulations are deterministic and come back as pickles, the reports
are functions of the folder's files.

The child is forked only from a top-level process, before the comparison's first solve, and only when a core
is idle (the load average a core below the cores this process may use): a worker of a multi-day pool has
siblings on the other cores already, daemonic workers may not have children, and on a busy machine the child
only competes with the parent (it costs about 5 % more CPU: its own start and the pages it shares).
Elsewhere (``fork`` unavailable, or it fails) :class:`Serial` does the same steps in-process, in the same
order.  An exception of the child is raised again in the parent, and a parent that stops (an error,
Ctrl-C, SIGKILL) ends the child: it kills it, or the child finds the pipe closed and exits.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import time
from collections.abc import Callable
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from rpbench.backends._forked import start_piped
from rpbench.exceptions import RpbenchError

OfflineFn = Callable[[], Any]
ReportFn = Callable[[Path, str], object]
#: Simulates the comparison's run of that index (its place in the spec's simulated runs).
SimulateFn = Callable[[int], Any]

#: Who took a run (:class:`Claims`).
_FREE, _PARENT, _CHILD = 0, 1, 2


class Claims:
    """Which process simulates each run: the parent takes every run from the front, in order; the child takes
    the ``movable`` ones (runs that need nothing from another) from the back.  A run is taken once, under a
    lock in memory both processes share, so the two meet and none is simulated twice."""

    def __init__(self, runs: int, movable: list[int]) -> None:
        ctx = multiprocessing.get_context("fork")
        self._taken = ctx.Array("b", max(runs, 1))  # shared by fork: _FREE, _PARENT or _CHILD per run
        self.movable = sorted(movable)

    def take(self, index: int, who: int) -> bool:
        with self._taken.get_lock():
            if self._taken[index] != _FREE:
                return False
            self._taken[index] = who
            return True


class Serial:
    """The steps in-process: the offline runs when they are asked for, report.md when the folder is ready, and
    every simulated run the parent's (:meth:`claim` is always true)."""

    def __init__(self, offline: OfflineFn, report: ReportFn, beside: ReportFn | None = None) -> None:
        self._offline, self._report, self._beside = offline, report, beside

    def offline(self) -> Any:
        return self._offline()

    def claim(self, index: int) -> bool:
        """May the parent simulate run ``index`` (False: the child has taken it)?"""
        return True

    def simulated(self) -> dict[int, Any]:
        """The runs the child simulated, by index (call after :meth:`offline`)."""
        return {}

    def report(self, folder: Path, name: str) -> None:
        if self._beside is not None:
            self._beside(folder, name)
        self._report(folder, name)

    def wait(self) -> None:
        """Return once report.md is written (in-process: it is)."""

    def close(self) -> None:
        """Nothing to end."""


class Forked(Serial):
    """The steps in a forked child; the same calls, each answered from the child."""

    def __init__(
        self,
        offline: OfflineFn,
        report: ReportFn,
        beside: ReportFn | None = None,
        *,
        warm_up: Callable[[], None],
        simulate: SimulateFn | None = None,
        claims: Claims | None = None,
    ) -> None:
        super().__init__(offline, report, beside)
        ctx = multiprocessing.get_context("fork")
        self._claims = claims if simulate is not None else None
        self._conn, child_end = ctx.Pipe(duplex=True)
        self._child = start_piped(
            _child_main,
            (child_end, self._conn, offline, report, beside, warm_up, simulate, self._claims),
            self._conn,
            child_end,
        )
        self._asked_report = False
        self._offline_value: tuple[Any] | None = None  # received once, kept
        self._runs: dict[int, Any] | None = None

    def offline(self) -> Any:
        if self._offline_value is None:
            self._offline_value = (self._answer("solving the offline runs"),)
        return self._offline_value[0]

    def claim(self, index: int) -> bool:
        return self._claims is None or self._claims.take(index, _PARENT)

    def simulated(self) -> dict[int, Any]:
        if self._runs is None:
            self.offline()  # the child answers in order: the offline runs first
            runs: dict[int, Any] = {}
            if self._claims is not None:
                while (answer := self._answer("simulating a run")) is not None:
                    index, run = answer
                    runs[index] = run
            self._runs = runs
        return self._runs

    def report(self, folder: Path, name: str) -> None:
        self._conn.send((folder, name))
        self._asked_report = True

    def wait(self) -> None:
        if self._asked_report:
            self._asked_report = False
            self._answer("writing report.md")

    def close(self) -> None:
        if self._child.is_alive():
            self._child.kill()
        self._child.join()
        self._conn.close()

    def _answer(self, what: str) -> Any:
        try:
            ok, value = self._conn.recv()
        except EOFError:
            raise RpbenchError(f"the second process died {what} (exit status {self._exit_status()})") from None
        if not ok:
            raise value
        return value

    def _exit_status(self) -> int | None:
        self._child.join(timeout=1.0)
        return self._child.exitcode


def start(
    offline: OfflineFn,
    report: ReportFn,
    beside: ReportFn | None = None,
    *,
    warm_up: Callable[[], None],
    simulate: SimulateFn | None = None,
    runs: int = 0,
    movable: list[int] | None = None,
) -> Serial:
    """The comparison's second process (:class:`Forked`) where it can run, else :class:`Serial`.

    ``offline()`` returns the offline runs; ``report(folder, name)`` writes report.md into ``folder``, and
    ``beside(folder, name)`` the part of it that can be drawn at the same time; ``warm_up()`` (in the child,
    between the offline runs and the report) imports what ``report`` needs.  ``simulate(i)`` simulates run
    ``i`` of ``runs``: the child may take those of ``movable`` the parent has not reached (:class:`Claims`).
    """
    if not may_fork():
        return Serial(offline, report, beside)
    try:
        claims = Claims(runs, movable) if simulate is not None and movable else None
        return Forked(offline, report, beside, warm_up=warm_up, simulate=simulate, claims=claims)
    except OSError:  # no process or memory to fork: the same work in-process
        return Serial(offline, report, beside)


def may_fork() -> bool:
    """Whether this process may fork a helper that pays: ``fork`` exists, this is a top-level process (a
    pool's workers have siblings on the other cores, and daemonic ones may not have children) and a core
    is idle (:func:`idle_core`)."""
    return (
        "fork" in multiprocessing.get_all_start_methods()
        and multiprocessing.parent_process() is None
        and not multiprocessing.current_process().daemon
        and idle_core()
    )


#: Looks at the processes running now (:func:`others_running`): how many, and how far apart.
RUNNING_SAMPLES, RUNNING_GAP_S = 5, 0.01


def idle_core() -> bool:
    """Is a core free for a second process: at least two cores for this process, and the load average a core
    below them, or, where the average still holds a load that has ended (the last command of a script, a
    benchmark's previous run), the other processes running right now half a core below that?"""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if cores < 2:
        return False
    return os.getloadavg()[0] <= cores - 1 or others_running() <= cores - 1.5


def others_running() -> float:
    """The mean number of other processes (and threads) running or ready to run, over a few samples of
    ``/proc/loadavg`` (Linux); infinite where it cannot be read."""
    counts = []
    for i in range(RUNNING_SAMPLES):
        if i:
            time.sleep(RUNNING_GAP_S)
        try:
            with open("/proc/loadavg", encoding="ascii") as f:
                running = int(f.read().split()[3].split("/")[0])
        except (OSError, ValueError, IndexError):
            return float("inf")
        counts.append(running - 1)  # this process is one of them
    return sum(counts) / len(counts)


def _child_main(
    conn: Connection,
    parent_end: Connection,
    offline: OfflineFn,
    report: ReportFn,
    beside: ReportFn | None,
    warm_up: Callable[[], None],
    simulate: SimulateFn | None,
    claims: Claims | None,
) -> None:
    parent_end.close()  # so that the parent's exit closes the pipe: recv() then ends this process
    # Ctrl-C and SIGTERM reach the whole process group: the parent stops, then ends this child itself
    # (start_piped set the signals so).
    try:
        # Everything is computed before anything is sent: a large answer waits in the pipe until the parent
        # reads it, after its own simulations, and the child must not wait there while runs are left to take.
        answers = [_answer_of(offline)]
        if simulate is not None and claims is not None:
            if answers[0][0]:
                answers += _simulate_from_the_back(simulate, claims)
            answers.append((True, None))  # no more runs
        for answer in answers:
            _post(conn, answer)
        warm_up()
        job = conn.recv()
        _send(conn, lambda: _both(report, beside, *job))
    except (EOFError, BrokenPipeError):  # the parent is gone or stopped listening
        pass
    finally:
        conn.close()


def _simulate_from_the_back(simulate: SimulateFn, claims: Claims) -> list[tuple[bool, Any]]:
    """The movable runs the parent has not taken, last first, each answered as :func:`_answer_of` does; stops
    at the first the parent took (the parent goes in order: the runs before it are its own or this loop's),
    or after an error (passed on: the parent raises it)."""
    answers: list[tuple[bool, Any]] = []
    for index in reversed(claims.movable):
        if not claims.take(index, _CHILD):
            break
        answers.append(_answer_of(functools.partial(_indexed, simulate, index)))
        if not answers[-1][0]:
            break
    return answers


def _indexed(simulate: SimulateFn, index: int) -> tuple[int, Any]:
    return index, simulate(index)


def _both(report: ReportFn, beside: ReportFn | None, folder: Path, name: str) -> None:
    """``report`` here and ``beside`` in a child of this process (forked with matplotlib loaded), both done."""
    if beside is None:
        report(folder, name)
        return
    side_by_side(lambda: report(folder, name), lambda: beside(folder, name), fork=True)


def side_by_side(here: Callable[[], Any], there: Callable[[], Any], *, fork: bool | None = None) -> tuple[Any, Any]:
    """``(here(), there())``, ``there`` run in a forked child meanwhile when ``fork`` (default: when
    :func:`may_fork`), else after ``here``; an exception of either is raised here, the child ended first.

    ``there``'s value comes back pickled.  A caller that knows the machine better than the load average
    does passes ``fork`` (a pool's parent whose workers just ended: their load is still in the average).
    """
    fork = may_fork() if fork is None else fork
    if not fork or "fork" not in multiprocessing.get_all_start_methods():
        return here(), there()
    ctx = multiprocessing.get_context("fork")
    conn, child_end = ctx.Pipe(duplex=False)
    helper = start_piped(_helper_main, (child_end, conn, there), conn, child_end)
    try:
        mine = here()
        try:
            ok, value = conn.recv()
        except EOFError:
            helper.join(timeout=1.0)
            raise RpbenchError(f"the process drawing beside this one died (exit status {helper.exitcode})") from None
        if not ok:
            raise value
        return mine, value
    finally:
        if helper.is_alive():
            helper.kill()
        helper.join()
        conn.close()


def _helper_main(conn: Connection, parent_end: Connection, fn: Callable[[], Any]) -> None:
    parent_end.close()
    try:
        _send(conn, fn)
    except BrokenPipeError:
        pass
    finally:
        conn.close()


def _send(conn: Connection, fn: Callable[[], Any]) -> bool:
    """``fn()``'s value, or the exception it raised, to the parent; whether ``fn`` returned."""
    answer = _answer_of(fn)
    return _post(conn, answer) and answer[0]


def _answer_of(fn: Callable[[], Any]) -> tuple[bool, Any]:
    """``(True, fn())``, or ``(False, the exception it raised)``."""
    try:
        return True, fn()
    except BaseException as exc:
        return False, exc


def _post(conn: Connection, answer: tuple[bool, Any]) -> bool:
    """``answer`` to the parent (one that cannot be pickled as one line naming it); whether it went as it was."""
    try:
        conn.send(answer)
    except (BrokenPipeError, EOFError):
        raise
    except Exception as exc:  # an unpicklable value or exception
        conn.send((False, RpbenchError(f"{type(answer[1]).__name__}: {answer[1]} (not passed on: {exc})")))
        return False
    return True
