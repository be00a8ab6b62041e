"""Solver backends: one adapter module per solver, one registry, presets, and the one entry point.

* :mod:`.base` — the :class:`Backend` interface and :class:`SolveOptions`;
* :mod:`.registry` — backend name -> adapter class (imported lazily: importing
  this package imports no solver library);
* :mod:`.presets` — ``--solver NAME`` = ``solvers/NAME.toml``;
* :mod:`.solve` — :func:`solve`, what the simulator, the oracle and the
  benchmark call: support and installation checked, the solution verified once.

Adding a backend is one adapter module, one :data:`BACKEND_REGISTRY` line and one
preset file.  A backend defined outside the package needs no registry line:
its preset names it as an installed entry point of the group
``rpbench.backends`` or as ``module:Class`` (:func:`backend_class`).
"""

from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.presets import Preset, load_preset, preset_names
from rpbench.backends.registry import BACKEND_REGISTRY, backend_class, get_backend
from rpbench.backends.solve import solve

__all__ = [
    "BACKEND_REGISTRY",
    "Backend",
    "Preset",
    "SolveOptions",
    "backend_class",
    "get_backend",
    "load_preset",
    "preset_names",
    "solve",
]
