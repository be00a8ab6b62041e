"""Dispatching strategies and their registry.

A strategy turns a read-only :class:`~rpbench.strategies.base.RoundState`
into a solver-agnostic :class:`~rpbench.strategies.base.RoundModel`; the
simulator solves and commits it.  To add a formulation, write one module
with a :class:`~rpbench.strategies.base.Strategy` subclass and register its
name here: its label, plot colour, options and calibration are class
attributes (:class:`~rpbench.strategies.base.Strategy`), which the harness,
the reports and the plots read.
"""

from __future__ import annotations

import importlib
from typing import Any

from rpbench.exceptions import ParameterError
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy

#: Strategy name -> "module:Class" (modules under rpbench.strategies).
REGISTRY: dict[str, str] = {
    "np": "myopic:NonPooling",
    "mb": "myopic:MyopicBatch",
    "rtv": "rtv:RTV",
    "fl-nd": "forward:ForwardLookingNoDelay",
    "fl": "forward:ForwardLooking",
}


def strategy_class(name: str) -> type[Strategy]:
    target = REGISTRY.get(name)
    if target is None:
        raise ParameterError(f"unknown strategy {name!r}; known strategies: {', '.join(REGISTRY)}")
    module_name, class_name = target.split(":")
    return getattr(importlib.import_module(f"{__name__}.{module_name}"), class_name)


def make_strategy(name: str, **options: Any) -> Strategy:
    return strategy_class(name)(**options)


__all__ = ["Kind", "REGISTRY", "RoundModel", "RoundState", "Strategy", "make_strategy",
           "strategy_class"]
