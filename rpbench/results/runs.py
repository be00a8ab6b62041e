"""How a run is called in tables and drawn in plots.

A results folder records each run's label and colour in ``meta.json``
(:mod:`rpbench.results.folder`), so a folder renders from its files alone,
plug-in strategies included: :func:`run_styles` reads them.  Without a record
(folders written before labels were recorded, tables built in code) the
label and colour are read off the strategy classes and offline runs; a run
name that resolves to no class is shown under its own name.  A run that read
the future (``"clairvoyant": true`` in its record, or a class declaring
``clairvoyant = True``) is labelled so: ``FL (clairvoyant)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.strategies import strategy_class

#: Run name -> (label, colour): what :func:`run_styles` returns and the ``styles`` arguments take.
Styles = Mapping[str, tuple[str, str | None]]
#: Appended to the label of a run that read the future.
CLAIRVOYANT_MARK = " (clairvoyant)"


def clairvoyant_runs(meta: Mapping[str, Any]) -> set[str]:
    """The runs of a folder's ``meta.json`` that read the future (their strategy was clairvoyant)."""
    runs = meta.get("runs") or {}
    return {name for name, record in runs.items() if isinstance(record, Mapping) and record.get("clairvoyant") is True}


def simulated_runs(meta: Mapping[str, Any], runs: Iterable[str]) -> list[str]:
    """The runs among ``runs`` that are simulations (meta.json's ``kind``; a run without a record: any name
    that is not an offline run's), in the order given."""
    records = meta.get("runs") or {}
    out = []
    for name in runs:
        record = records.get(name)
        kind = record.get("kind") if isinstance(record, Mapping) else None
        if kind == "simulation" or (kind is None and name not in ORACLE_RUNS):
            out.append(name)
    return out


def run_styles(meta: Mapping[str, Any]) -> dict[str, tuple[str, str | None]]:
    """The label and colour of every run a folder's ``meta.json`` records (others fall back to the classes)."""
    out = {}
    clairvoyant = clairvoyant_runs(meta)
    for name, record in (meta.get("runs") or {}).items():
        if isinstance(record, Mapping) and isinstance(record.get("label"), str):
            color = record.get("color")
            label = record["label"] + (CLAIRVOYANT_MARK if name in clairvoyant else "")
            out[name] = (label, color if isinstance(color, str) else None)
    return out


def run_label(name: str, styles: Styles | None = None) -> str:
    """Column header / legend entry of a run (``fl-nd`` -> ``FL-no_delay``)."""
    return _style(name, styles)[0]


def markdown_cell(text: str) -> str:
    """``text`` (a run label, a run name, a scenario label: anything a user or plug-in chose) as one cell of
    a markdown table: ``|`` escaped (it would end the cell), line breaks and runs of spaces made one space."""
    return " ".join(str(text).split()).replace("|", "\\|")


def run_color(name: str, styles: Styles | None = None) -> str | None:
    """Matplotlib colour of a run's line (None: the next colour of the cycle)."""
    return _style(name, styles)[1]


def _style(name: str, styles: Styles | None) -> tuple[str, str | None]:
    if styles and name in styles:
        return styles[name]
    if name in ORACLE_RUNS:
        run = ORACLE_RUNS[name]
        return run.label, run.color
    try:
        cls = strategy_class(name)
    except Exception:  # a label is cosmetic: a broken or missing plug-in must not stop a report
        return name, None
    # a class attribute True, not a property that depends on the options
    return cls.label + (CLAIRVOYANT_MARK if getattr(cls, "clairvoyant", False) is True else ""), cls.color
