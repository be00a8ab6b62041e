"""rpbench: an optimisation-modelling benchmark suite for dynamic ride-pooling dispatch.

Implements Wang, Yang, Feng, Hu, He, "A prediction-based forward-looking vehicle dispatching strategy for
dynamic ride-pooling" on the real Haikou road network and DiDi orders, and on any other city's (Manhattan's
yellow-cab trips are built in; docs/cities.md).

The names a user needs are here, each from the module that defines it::

    from rpbench import RunSpec, ScenarioRequest, run_comparison
    outcome = run_comparison(RunSpec.of(ScenarioRequest("toy", sample=0.5), ["mb", "fl", "bound"]), "my-run")

A name is imported when it is first used, so ``import rpbench`` stays light (it loads no solver library,
no plotting library and no simulator): a command that needs one module pays for that module only.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from rpbench.version import __version__

if TYPE_CHECKING:  # the same names as _FACE, for type checkers and editors
    from rpbench.check import check_folder as check_folder
    from rpbench.check import check_tree as check_tree
    from rpbench.harness.comparison import run_comparison as run_comparison
    from rpbench.harness.evaluate import run_evaluation as run_evaluation
    from rpbench.harness.multiday import run_days as run_days
    from rpbench.harness.outcome import Outcome as Outcome
    from rpbench.model import Structure as Structure
    from rpbench.options import Range as Range
    from rpbench.options import RunOptions as RunOptions
    from rpbench.options import option as option
    from rpbench.protocols import load_protocol as load_protocol
    from rpbench.scenarios.request import ScenarioRequest as ScenarioRequest
    from rpbench.spec import RunSpec as RunSpec
    from rpbench.strategies.base import RoundModel as RoundModel
    from rpbench.strategies.base import RoundState as RoundState
    from rpbench.strategies.base import Strategy as Strategy
    from rpbench.strategies.candidates import NO_WAIT_UTILITY_M as NO_WAIT_UTILITY_M
    from rpbench.strategies.candidates import assignment_round as assignment_round
    from rpbench.strategies.candidates import join_options as join_options
    from rpbench.strategies.candidates import vacant_options as vacant_options

#: The public face: each name and the module that defines it.
_FACE = {
    # run a comparison, many days or a protocol, and what comes back
    "RunSpec": "rpbench.spec",
    "ScenarioRequest": "rpbench.scenarios.request",
    "run_comparison": "rpbench.harness.comparison",
    "run_days": "rpbench.harness.multiday",
    "run_evaluation": "rpbench.harness.evaluate",
    "load_protocol": "rpbench.protocols",
    "Outcome": "rpbench.harness.outcome",
    # check a results folder
    "check_folder": "rpbench.check",
    "check_tree": "rpbench.check",
    # write a strategy
    "Strategy": "rpbench.strategies.base",
    "RoundState": "rpbench.strategies.base",
    "RoundModel": "rpbench.strategies.base",
    "Structure": "rpbench.model",
    "RunOptions": "rpbench.options",
    "option": "rpbench.options",
    "Range": "rpbench.options",
    "vacant_options": "rpbench.strategies.candidates",
    "join_options": "rpbench.strategies.candidates",
    "assignment_round": "rpbench.strategies.candidates",
    "NO_WAIT_UTILITY_M": "rpbench.strategies.candidates",
}

__all__ = ["__version__", *_FACE]


def __getattr__(name: str) -> Any:
    """A name of the face, imported from its module on first use (PEP 562)."""
    module = _FACE.get(name)
    if module is None:
        raise AttributeError(f"module 'rpbench' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # the next lookup is an ordinary attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
