"""Backend registry: name -> adapter class, imported lazily.

Importing it imports no solver library; :func:`get_backend`
imports the adapter module (which itself imports its solver only when it
solves).
"""

from __future__ import annotations

import importlib

from rpbench.backends.base import Backend
from rpbench.exceptions import PresetError

#: Backend name -> "module:Class" (modules under rpbench.backends).
REGISTRY: dict[str, str] = {
    "highs": "highs:HighsBackend",
    "ortools": "ortools:OrtoolsBackend",
    "pyomo": "pyomo:PyomoBackend",
    "cvxpy": "cvxpy:CvxpyBackend",
    "scipy": "scipy:ScipyBackend",
    "matching": "matching:MatchingBackend",
    "blossom": "blossom:BlossomBackend",
}


def backend_class(name: str) -> type[Backend]:
    target = REGISTRY.get(name)
    if target is None:
        raise PresetError(f"unknown backend {name!r}; known backends: {', '.join(REGISTRY)}")
    module_name, class_name = target.split(":")
    module = importlib.import_module(f"rpbench.backends.{module_name}")
    return getattr(module, class_name)


def get_backend(name: str) -> Backend:
    """An instance of the named backend (raises if its library is missing)."""
    cls = backend_class(name)
    cls.ensure_installed()
    return cls()

