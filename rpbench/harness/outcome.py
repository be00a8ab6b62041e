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
from typing import NamedTuple

import pandas as pd

from rpbench.results.ratios import BOUND, best_known, savings_of
from rpbench.results.read import load_kpis, over_budget_runs, unproven_runs
from rpbench.results.runs import run_label, simulated_runs


class Bracket(NamedTuple):
    """Where the optimum lies: ``lb_km`` (the best known schedule, run ``lb_run``) <= OPT <= ``u_km`` (the
    proven upper bound; None without a ``bound`` run).  docs/bound.md proves both sides."""

    lb_km: float
    lb_run: str
    u_km: float | None


@dataclass(frozen=True, repr=False)
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

    @property
    def savings(self) -> pd.Series:
        """Each run's total distance saving (km), in the table's run order (empty when the table has none)."""
        if "total_saving_km" not in self.table.index:
            return pd.Series(dtype=float, name="total_saving_km")
        return self.table.loc["total_saving_km"].astype(float)

    @property
    def bracket(self) -> Bracket | None:
        """[LB, U] around the optimum's saving (docs/bound.md; kpis.csv's bracket rows), from the table's
        runs; None without a simulated run."""
        runs = [str(c) for c in self.table.columns]
        lb = best_known(savings_of(self.table, simulated_runs({}, runs)))
        if lb is None:
            return None
        u = float(self.savings[BOUND]) if BOUND in runs else None
        return Bracket(lb.saving_km, lb.run, u)

    def __repr__(self) -> str:
        """What a reader at a Python prompt wants first: where the folder is, each run's saving, the bracket,
        and the runs to be careful with (the full KPI table is ``table``)."""
        kind = f", {len(self.children)} children" if self.children else ""
        lines = [f"Outcome({str(self.folder)!r}{kind})"]
        if len(self.savings):
            cells = ", ".join(f"{run_label(str(r))} {v:,.1f}" for r, v in self.savings.items())
            lines.append(f"  saving (km): {cells}")
        bracket = self.bracket
        if bracket is not None:
            upper = "no upper bound run" if bracket.u_km is None else f"U = {bracket.u_km:,.1f}"
            lines.append(f"  OPT in [LB, U]: LB = {bracket.lb_km:,.1f} ({run_label(bracket.lb_run)}), {upper}")
        for where, kind_, run, why in self.remarks():
            place = f"{where}: " if where else ""
            lines.append(f"  {place}{run_label(run)} {kind_.replace('_', ' ')}: {why}")
        lines.append("  (.folder, .table: KPI rows x runs, .savings, .bracket, .children)")
        return "\n".join(lines)

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
