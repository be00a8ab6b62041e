"""How a run is called in tables and drawn in plots: read off the strategy classes and oracle runs.

A run name that is neither (say, a plug-in strategy that is not installed
where a folder is re-rendered) is shown under its own name.
"""

from __future__ import annotations

from rpbench.exceptions import ParameterError
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
    except (ParameterError, ImportError):
        return name, None
    return cls.label, cls.color
