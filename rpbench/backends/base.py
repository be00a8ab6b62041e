"""The backend interface every solver adapter implements.

A backend turns a :mod:`rpbench.model` object into its solver's own model,
solves it and returns a :class:`~rpbench.model.Solution`.  It imports its
solver library only inside its methods (``import rpbench`` loads no solver),
declares the structures it solves *exactly*, and raises
:class:`~rpbench.exceptions.SolverNotInstalledError` with a clear message when
its library is missing.  A time limit that stops a solve returns the
incumbent with status ``TIME_LIMIT`` — never a silently wrong answer.
"""

from __future__ import annotations

import importlib.util
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

from rpbench.exceptions import SolverNotInstalledError
from rpbench.model import Model, Solution, Structure

#: Solver libraries found installed in this process.  A library once found stays installed, so a backend
#: checks each only until it is found; a missing one is looked for again at every check (it may be
#: installed meanwhile), which is only the error path.  Every solve checks: a path search per library
#: and solve (a library not imported yet, such as highspy under the matching preset, where it is only the
#: fallback) was a sixth of Hindsight's round loop.
_FOUND: set[str] = set()


def _installed(library: str) -> bool:
    if library not in _FOUND and importlib.util.find_spec(library) is not None:
        _FOUND.add(library)
    return library in _FOUND


@dataclass(frozen=True)
class SolveOptions:
    """Options a preset passes to its backend (``solvers/NAME.toml`` ``[options]``).

    ``threads``/``time_limit_s`` ``None`` mean the solver's default.
    ``mip_rel_gap`` defaults to 0: rpbench wants proven optima.  ``method``
    picks an algorithm where a backend offers several (e.g. ``"lp"`` or
    ``"mip"`` for HiGHS on the assignment).  ``extra`` holds backend-specific
    settings passed through verbatim.
    """

    threads: int | None = 1
    time_limit_s: float | None = None
    mip_rel_gap: float = 0.0
    method: str | None = None
    solver: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)


class Backend(ABC):
    """One solver adapter.  Subclasses set the class attributes and ``solve``."""

    #: Registry name (``backend = "..."`` in a preset).
    name: ClassVar[str]
    #: Import names of the libraries this backend needs.
    requires: ClassVar[tuple[str, ...]]
    #: Structures this backend solves to proven optimality.
    exact: ClassVar[frozenset[Structure]]
    #: One line for ``rpbench list``.
    description: ClassVar[str] = ""
    #: Whether :meth:`solve` takes ``hint=`` (a feasible 0/1 column vector to warm-start from); only then
    #: does :func:`rpbench.backends.solve` pass one.
    accepts_hint: ClassVar[bool] = False

    @classmethod
    def missing_libraries(cls) -> list[str]:
        return [lib for lib in cls.requires if not _installed(lib)]

    @classmethod
    def is_installed(cls) -> bool:
        return not cls.missing_libraries()

    @classmethod
    def ensure_installed(cls) -> None:
        missing = cls.missing_libraries()
        if missing:
            raise SolverNotInstalledError(
                f"backend {cls.name!r} needs the Python package(s) {', '.join(missing)}, which are not "
                f"installed; install them (pip install {' '.join(missing)}) or choose another --solver"
            )

    def supports(self, structure: Structure) -> bool:
        return structure in self.exact

    def load(self) -> None:  # noqa: B027 - optional: most backends have nothing to load ahead
        """Import the solver library now, before a run's first solve (default: nothing to do ahead)."""

    @abstractmethod
    def solve(self, model: Model, options: SolveOptions) -> Solution:
        """Solve ``model`` and return a validated solution (a backend with :attr:`accepts_hint` also takes
        ``hint=``)."""
