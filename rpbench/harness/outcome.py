"""What a harness call wrote and knows: its folder, its KPI table, and the runs a reader must be told of.

:func:`~rpbench.harness.comparison.run_comparison`, :func:`~rpbench.harness.multiday.run_days`,
:func:`~rpbench.harness.sweep.run_sweep` and :func:`~rpbench.harness.evaluate.run_evaluation` return an
:class:`Outcome`, so that a caller prints from what the harness knew when it wrote the folder instead of
reading the folder back.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from rpbench.results.read import load_kpis, over_budget_runs, unproven_runs


@dataclass(frozen=True)
class Outcome:
    """A results folder the harness wrote, with what it knows of it.

    ``table`` is a comparison's KPI rows x run columns (with its ratio and bracket rows); a parent's
    (multi-day run, sweep, evaluation) is the mean over its children.  ``unproven`` maps each run whose
    numbers rest on solver answers not proven optimal to why; ``over_budget`` each run with rounds slower
    than the decision budget to how many.  A parent's ``children`` hold its days, points or units.
    """

    folder: Path
    table: pd.DataFrame
    unproven: dict[str, str] = field(default_factory=dict)
    over_budget: dict[str, str] = field(default_factory=dict)
    children: tuple[Outcome, ...] = ()
    #: False for a folder found written already (a resumed evaluation's unit), read back from its files.
    fresh: bool = True

    @classmethod
    def read(cls, folder: Path) -> Outcome:
        """The outcome of a comparison folder written earlier (a resumed evaluation's unit), from its files."""
        table = load_kpis(folder)
        return cls(folder, table, unproven_runs(folder), over_budget_runs(folder), fresh=False)

    def moved_to(self, folder: Path) -> Outcome:
        """This outcome, its folder (and its children's, inside it) renamed to ``folder``."""
        children = tuple(c.moved_to(folder / c.folder.name) for c in self.children)
        return dataclasses.replace(self, folder=folder, children=children)

    def unproven_runs(self) -> dict[str, str]:
        """Every run of this folder or of a child that rests on unproven answers, with its first reason."""
        found = dict(self.unproven)
        for child in self.children:
            for run, why in child.unproven_runs().items():
                found.setdefault(run, why)
        return found

    def remarks(self) -> Iterator[tuple[str, str, str, str]]:
        """``(where, kind, run, why)``: every unproven run (kind ``unproven``), then every run over the decision
        budget (kind ``over_budget``), this folder's first and then its children's (``where``: the child's
        folder name; empty for this folder)."""
        places = [("", self), *((c.folder.name, c) for c in self.children)]
        for where, outcome in places:
            for run, why in outcome.unproven.items():
                yield where, "unproven", run, why
        for where, outcome in places:
            for run, what in outcome.over_budget.items():
                yield where, "over_budget", run, what
