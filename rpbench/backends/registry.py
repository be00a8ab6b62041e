"""Backend registry: name -> adapter class, imported lazily.

Importing it imports no solver library; :func:`get_backend`
imports the adapter module (which itself imports its solver only when it
solves).  Backends defined outside the package are named by an installed
entry point of the group ``rpbench.backends`` or as ``module:Class``
(:func:`backend_class`, :mod:`rpbench.plugins`).
"""

from __future__ import annotations

from rpbench import plugins
from rpbench.backends.base import Backend
from rpbench.exceptions import PresetError

#: Backend name -> "module:Class" (modules under rpbench.backends).
BACKEND_REGISTRY: dict[str, str] = {
    "highs": "highs:HighsBackend",
    "ortools": "ortools:OrtoolsBackend",
    "pyomo": "pyomo:PyomoBackend",
    "cvxpy": "cvxpy:CvxpyBackend",
    "scipy": "scipy:ScipyBackend",
    "matching": "matching:MatchingBackend",
    "blossom": "blossom:BlossomBackend",
}

#: The preset options (``[options]`` keys) each built-in backend honours; a preset setting another one is
#: refused (it would be dropped silently yet recorded in meta.json as used).  ``method`` picks among a
#: backend's algorithms (HiGHS, SciPy: lp or mip for the assignment; OR-Tools: flow or cp), ``solver`` the
#: solver behind a modelling layer (CVXPY, Pyomo); SciPy's milp runs on one thread; the special-purpose
#: algorithms of matching and blossom are exact and have no method to choose nor gap to accept.
#: A plug-in backend declares its own as a class attribute ``honours`` (default: every option).
PRESET_OPTIONS = frozenset({"threads", "time_limit_s", "mip_rel_gap", "method", "solver", "extra"})
HONOURS: dict[str, frozenset[str]] = {
    "highs": PRESET_OPTIONS - {"solver"},
    "ortools": PRESET_OPTIONS - {"solver"},
    "scipy": PRESET_OPTIONS - {"solver", "threads"},
    "cvxpy": PRESET_OPTIONS,
    "pyomo": PRESET_OPTIONS,
    "matching": frozenset({"threads", "time_limit_s", "extra"}),
    "blossom": frozenset({"threads", "time_limit_s", "extra"}),
}

#: Entry-point group of backends installed by other distributions.
BACKEND_ENTRY_POINTS = "rpbench.backends"


def backend_class(name: str) -> type[Backend]:
    """The adapter class of a backend name, or one :class:`PresetError` line.

    ``name`` is, in this order of precedence, a built-in name of
    :data:`BACKEND_REGISTRY`; a ``module:Class`` spec (the module imported by its
    absolute name: installed or on ``PYTHONPATH``); or the name of an
    installed entry point of :data:`BACKEND_ENTRY_POINTS` (compared
    case-insensitively).  An entry point named like a built-in backend is
    ignored: the built-in always wins.  The class must subclass
    :class:`Backend`, implement ``solve`` and declare ``name``, ``requires``
    and ``exact``.
    """
    return plugins.resolve(
        name,
        builtin=BACKEND_REGISTRY,
        package="rpbench.backends",
        group=BACKEND_ENTRY_POINTS,
        base=Backend,
        what="backend",
        required=("name", "requires", "exact"),
        error=PresetError,
    )


def backend_plugin_names() -> list[str]:
    """Names of the installed plug-in backends (entry points not shadowed by a built-in name)."""
    return plugins.plugin_names(BACKEND_ENTRY_POINTS, BACKEND_REGISTRY)


def honoured_options(name: str) -> frozenset[str]:
    """The preset options backend ``name`` honours (:data:`HONOURS`; a plug-in's ``honours`` attribute)."""
    if name in HONOURS:
        return HONOURS[name]
    declared = getattr(backend_class(name), "honours", None)
    return frozenset(declared) & PRESET_OPTIONS if declared is not None else PRESET_OPTIONS


def get_backend(name: str) -> Backend:
    """An instance of the named backend (raises if its library is missing)."""
    cls = backend_class(name)
    cls.ensure_installed()
    return cls()
