"""Whether a built-in strategy reads the future under a run's recorded options, from its class alone.

meta.json records per run what the simulator saw (``"clairvoyant": true``, :func:`~.runs.clairvoyant_runs`);
this module says what the strategy class declares (:attr:`~rpbench.strategies.base.Strategy.clairvoyant`)
for the options the run recorded, so that a flag edited to false is caught (``rpbench check``'s
``clairvoyant``) and an evaluation ranks such a run apart whatever its flag says.  A plug-in's class is not
imported for this: its recorded flag is taken as written.  What the class cannot say without the scenario
(FL's ``rates=auto`` on a scenario without demand history, :meth:`~rpbench.strategies.base.Strategy.clairvoyant_on`)
rests on the recorded flag too.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rpbench.exceptions import RpbenchError
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class


def declared_clairvoyant(name: str, record: Mapping[str, Any]) -> bool | None:
    """Whether run ``name``'s strategy reads the future under its recorded options (meta.json ``record``);
    None when that is not known here: not a simulation of a built-in strategy, or options it cannot read."""
    source = record.get("source", name)
    if record.get("kind") != "simulation" or not isinstance(source, str) or source not in STRATEGY_REGISTRY:
        return None
    options = record.get("options")
    try:
        cls = strategy_class(source)
        strategy = cls(cls.Options.parse(source, options if isinstance(options, dict) else {}))
    except (RpbenchError, TypeError, ValueError):  # options of another rpbench version
        return None
    return bool(strategy.clairvoyant)


def reads_future(name: str, record: Mapping[str, Any]) -> bool:
    """Whether a run read the future: its recorded flag, or its built-in strategy's class under its options."""
    return record.get("clairvoyant") is True or declared_clairvoyant(name, record) is True
