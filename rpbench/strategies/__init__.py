"""Dispatching strategies and their registry.

A strategy turns a read-only :class:`~rpbench.strategies.base.RoundState`
into a solver-agnostic :class:`~rpbench.strategies.base.RoundModel`; the
simulator solves and commits it.  To add a formulation, write one module
with a :class:`~rpbench.strategies.base.Strategy` subclass and register its
name here: its label, plot colour, options and calibration are class
attributes (:class:`~rpbench.strategies.base.Strategy`), which the harness,
the reports and the plots read.

A strategy defined outside the package runs the same way, named either by
an installed entry point of the group ``rpbench.strategies`` (``greedy =
"mypkg.rules:Greedy"`` in its ``pyproject.toml``) or directly as
``mypkg.rules:Greedy`` (:func:`strategy_class`, :mod:`rpbench.plugins`).
"""

from __future__ import annotations

from typing import Any

from rpbench import plugins
from rpbench.exceptions import ParameterError
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy

#: Strategy name -> "module:Class" (modules under rpbench.strategies).
STRATEGY_REGISTRY: dict[str, str] = {
    "np": "myopic:NonPooling",
    "mb": "myopic:MyopicBatch",
    "rtv": "rtv:RTV",
    "fl-nd": "forward:ForwardLookingNoDelay",
    "fl": "forward:ForwardLooking",
    "vf": "value:ValueFunction",
    "hindsight": "hindsight:Hindsight",
    "exact": "exact:Exact",
    "fl-perfect": "perfect:ForwardPerfect",
    "msa": "msa:MultipleScenario",
    "external": "external:External",
    "agent": "agent:Agent",
}

#: Entry-point group of strategies installed by other distributions.
STRATEGY_ENTRY_POINTS = "rpbench.strategies"


def strategy_class(name: str) -> type[Strategy]:
    """The strategy class of a run name, or one :class:`ParameterError` line.

    ``name`` is, in this order of precedence, a built-in name of
    :data:`STRATEGY_REGISTRY`; a ``module:Class`` spec (the module imported by its
    absolute name: installed or on ``PYTHONPATH``); or the name of an
    installed entry point of :data:`STRATEGY_ENTRY_POINTS` (compared
    case-insensitively).  An entry point named like a built-in strategy is
    ignored: the built-in always wins (and the harness gives the oracle runs
    ``bound``, ``oracle1``, ``oracle2`` precedence over both).  The class
    must subclass :class:`Strategy`, implement ``build`` and declare
    ``name``, ``label`` and ``structure``.
    """
    return plugins.resolve(
        name,
        builtin=STRATEGY_REGISTRY,
        package=__name__,
        group=STRATEGY_ENTRY_POINTS,
        base=Strategy,
        what="strategy",
        required=("name", "label", "structure"),
        error=ParameterError,
    )


def strategy_plugin_names() -> list[str]:
    """Names of the installed plug-in strategies (entry points not shadowed by a built-in name)."""
    return plugins.plugin_names(STRATEGY_ENTRY_POINTS, STRATEGY_REGISTRY)


def make_strategy(name: str, **options: Any) -> Strategy:
    return strategy_class(name)(**options)


__all__ = [
    "STRATEGY_ENTRY_POINTS",
    "STRATEGY_REGISTRY",
    "Kind",
    "RoundModel",
    "RoundState",
    "Strategy",
    "make_strategy",
    "strategy_class",
    "strategy_plugin_names",
]
