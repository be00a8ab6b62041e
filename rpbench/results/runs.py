"""How a run is called in tables and drawn in plots: read off the strategy classes and oracle runs.

A plug-in strategy (an entry-point name or a ``module:Class`` run name) is
shown by its class's ``label`` and ``color`` like a built-in one.  A run name
that resolves to no class (say, a plug-in that is not installed where a
folder is re-rendered) is shown under its own name.
"""

from __future__ import annotations

from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.strategies import strategy_class


def run_label(name: str) -> str:
    """Column header / legend entry of a run (``fl-nd`` -> ``FL-no_delay``)."""
    return _style(name)[0]


def run_color(name: str) -> str | None:
    """Matplotlib colour of a run's line (None: the next colour of the cycle)."""
    return _style(name)[1]


def _style(name: str) -> tuple[str, str | None]:
    if name in ORACLE_RUNS:
        run = ORACLE_RUNS[name]
        return run.label, run.color
    try:
        cls = strategy_class(name)
    except Exception:  # a label is cosmetic: a broken or missing plug-in must not stop a report
        return name, None
    return cls.label, cls.color
