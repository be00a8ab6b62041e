"""A comparison folder's tables read back from its files: the wide KPI table, and what its rounds and
``meta.json`` say of its runs (unproven answers, rounds over the decision budget).

Reports, the harness and the commands read a folder through these, so every reader sees one table.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench.exceptions import ResultsError
from rpbench.results import store as results
from rpbench.results.legacy import current_names
from rpbench.results.metrics import DECISION_PARTS
from rpbench.results.ratios import with_ratios
from rpbench.results.runs import simulated_runs


def load_kpis(folder: Path) -> pd.DataFrame:
    """Wide KPI table (rows = KPI keys, columns = runs in meta.json's order; older KPI names read as today's,
    :mod:`rpbench.results.legacy`), its ratio and bracket rows recomputed (:func:`~.ratios.with_ratios`)."""
    meta = results.read_meta(folder)
    tidy = results.read_csv(folder / "kpis.csv")
    missing = {"run", "kpi", "value"} - set(tidy.columns)
    if missing:
        raise ResultsError(f"{str(folder / 'kpis.csv')!r} lacks column(s) {', '.join(sorted(missing))}")
    values = pd.to_numeric(tidy["value"], errors="coerce")
    bad = values.isna() & tidy["value"].notna()
    if bad.any():
        row = tidy[bad].iloc[0]
        raise ResultsError(
            f"{str(folder / 'kpis.csv')!r}: run {row['run']!r}, KPI {row['kpi']!r} holds {row['value']!r}, "
            "which is not a number"
        )
    wide = current_names(tidy.assign(value=values)).pivot(index="kpi", columns="run", values="value")
    order = [r for r in meta.get("strategies", []) if r in wide.columns] + [
        r for r in wide.columns if r not in meta.get("strategies", [])
    ]
    return with_ratios(wide[order], simulated_runs(meta, order))


def unproven_runs(folder: Path) -> dict[str, str]:
    """The runs of a results folder whose numbers rest on solver answers not proven optimal, each with why
    ("3 of 95 rounds ended unproven (time_limit 3)", "stopped with status time_limit (gap unknown)"), in
    the folder's run order.  Read from the files alone, like every report."""
    meta = results.read_meta(folder)
    path = folder / "rounds.csv.gz"
    rounds = pd.read_csv(path, usecols=["run", "status"]) if path.is_file() else None
    return unproven_in(rounds, meta.get("runs", {}), meta.get("strategies", []))


def unproven_in(
    rounds: pd.DataFrame | None, records: Mapping[str, Mapping[str, Any]], order: Sequence[str]
) -> dict[str, str]:
    """:func:`unproven_runs` of a folder's ``rounds`` table (columns ``run``, ``status``), its meta.json run
    ``records`` and run ``order``: what the writer knows without reading the folder back."""
    found: dict[str, str] = {}
    if rounds is not None:
        for run, status in rounds.groupby("run", sort=False)["status"]:
            bad = status[status != "optimal"].value_counts()
            if len(bad):
                kinds = ", ".join(f"{s} {n}" for s, n in bad.items())
                found[str(run)] = f"{int(bad.sum())} of {len(status)} rounds ended unproven ({kinds})"
    for run, facts in records.items():
        if facts.get("kind") == "oracle" and facts.get("status", "optimal") != "optimal":
            gap = facts.get("gap")
            found[run] = (
                f"stopped with status {facts['status']} "
                f"(gap {'unknown' if gap is None or gap != gap else f'{gap:.3g}'})"
            )
    return dict(sorted(found.items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order)))


def decision_budget_of(meta: dict[str, Any]) -> float | None:
    """The decision budget (s) a folder's meta.json records, None without one (or with one that is not a
    number > 0, which ``rpbench check`` fails)."""
    budget = meta.get("decision_budget_s")
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not 0 < budget < math.inf:
        return None
    return float(budget)


def over_budget_runs(folder: Path) -> dict[str, str]:
    """The runs of a results folder with rounds slower than its decision budget (meta.json's
    ``decision_budget_s``), each with how many and the slowest ("3 of 346 rounds decided slower than the
    0.5 s budget (slowest 1.21 s)"), in the folder's run order; nothing without a budget."""
    budget = decision_budget_of(results.read_meta(folder))
    path = folder / "rounds.csv.gz"
    if budget is None or not path.is_file():
        return {}
    return over_budget_in(pd.read_csv(path), budget)


def over_budget_in(rounds: pd.DataFrame | None, budget: float | None) -> dict[str, str]:
    """:func:`over_budget_runs` of a folder's ``rounds`` table and decision ``budget`` (s; None: no budget)."""
    if budget is None or rounds is None:
        return {}
    rounds = rounds.assign(decision_s=rounds[list(DECISION_PARTS)].sum(axis=1))
    found = {}
    for run, decision in rounds.groupby("run", sort=False)["decision_s"]:
        over = int((decision > budget).sum())
        if over:
            found[str(run)] = (
                f"{over} of {len(decision)} rounds decided slower than the {budget:g} s budget "
                f"(slowest {decision.max():.3g} s)"
            )
    return found
