"""A strategy's competitive ratio as an interval, and the bracket [LB, U] around the optimum.

OPT is the largest total saving of any run of rpbench's simulator on a scenario that passes
``rpbench check``.  Two numbers of a results folder bracket it:

* U, the proven upper bound (the ``bound`` run, docs/bound.md): OPT <= U;
* LB, the best known schedule (``best_known_saving_km``): the largest total saving among the folder's
  simulated runs, online or clairvoyant.  Each of them is a schedule the simulator executed and the
  checker verifies, so OPT >= LB.

So the competitive ratio saving / OPT of a strategy lies in [saving / U, saving / LB]: the KPIs
``competitive_ratio_bound`` and ``competitive_ratio_best_known``, kept for every simulated run.
``bound_over_best_known`` = U / LB says how wide the bracket is.  ``saving_over_oracle1`` divides by the
paper's Oracle-1, which bounds nothing (a strategy that pairs en route can save more): a reference only.
A ratio whose denominator is not > 0 is undefined (NaN).  Offline runs get no ratio: they are not
schedules of the simulator.

These rows are derived from the other runs of a table, so a report drops and recomputes them
(:func:`with_ratios`) rather than trusting a stored copy; kpis.csv keeps them for scripts, the ratios
as rows of each simulated run and LB and U / LB as rows of the ``bound`` run, and meta.json names the
run that gave LB (``best_known``); ``rpbench check`` recomputes all of them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass

import pandas as pd

from rpbench.results.runs import Styles, run_label

#: The offline runs the ratios divide by.
BOUND, ORACLE1 = "bound", "oracle1"
#: A simulated run's saving over U, over LB and over Oracle-1's saving.
RATIO_KPIS = ("competitive_ratio_bound", "competitive_ratio_best_known", "saving_over_oracle1")
#: The ratio rows that divide by an offline run's saving, with that run.
DENOMINATORS = {"competitive_ratio_bound": BOUND, "saving_over_oracle1": ORACLE1}
#: The bracket: LB and U / LB, rows of the ``bound`` run (only with one).
BRACKET_KPIS = ("best_known_saving_km", "bound_over_best_known")
#: Every row derived from the other runs of a comparison.
DERIVED_KPIS = (*RATIO_KPIS, *BRACKET_KPIS)
#: meta.json's record of the best known schedule: ``{"run": name, "saving_km": LB}`` (null without a
#: simulated run).
BEST_KNOWN_FIELD = "best_known"
#: How the line under a comparison table starts (the checker finds it there).
BRACKET_PREFIX = "OPT "


def over(numerator: float, denominator: float | None) -> float:
    """``numerator / denominator``, NaN unless the denominator is a number > 0."""
    if denominator is None or not denominator > 0:
        return math.nan
    return float(numerator) / float(denominator)


@dataclass(frozen=True)
class BestKnown:
    """The best known schedule: the simulated run with the largest total saving (LB)."""

    run: str
    saving_km: float

    def record(self) -> dict[str, object]:
        """As meta.json records it (:data:`BEST_KNOWN_FIELD`)."""
        return {"run": self.run, "saving_km": self.saving_km}


def best_known(savings: Mapping[str, float]) -> BestKnown | None:
    """The simulated run of ``savings`` (run -> total saving, km) that saved the most, the first of equals in
    the mapping's order; None without a run with a saving."""
    known = {run: float(s) for run, s in savings.items() if s == s}  # an undefined saving is no schedule
    if not known:
        return None
    run = max(known, key=known.__getitem__)
    return BestKnown(run, known[run])


def derived_rows(savings: Mapping[str, float], offline: Mapping[str, float]) -> dict[str, dict[str, float]]:
    """Run -> KPI -> value of the derived rows: the ratios of each simulated run (``savings``, run -> total
    saving) and, with a bound among the ``offline`` runs (run -> total saving), the bracket as the bound's."""
    lb = best_known(savings)
    bound, oracle1 = offline.get(BOUND), offline.get(ORACLE1)
    out: dict[str, dict[str, float]] = {}
    for run, saving in savings.items():
        row = {}
        if bound is not None:
            row["competitive_ratio_bound"] = over(saving, bound)
        if lb is not None:
            row["competitive_ratio_best_known"] = over(saving, lb.saving_km)
        if oracle1 is not None:
            row["saving_over_oracle1"] = over(saving, oracle1)
        out[run] = row
    if bound is not None and lb is not None:
        out[BOUND] = {"best_known_saving_km": lb.saving_km, "bound_over_best_known": over(bound, lb.saving_km)}
    return out


def savings_of(wide: pd.DataFrame, runs: Collection[str]) -> dict[str, float]:
    """Total saving of the columns of ``wide`` (KPI rows x run columns) that are in ``runs``, in column order."""
    if "total_saving_km" not in wide.index:
        return {}
    row = wide.loc["total_saving_km"]
    return {str(c): float(row[c]) for c in wide.columns if c in runs}


def with_ratios(wide: pd.DataFrame, simulated: Collection[str]) -> pd.DataFrame:
    """``wide`` (KPI rows x run columns) with its :data:`DERIVED_KPIS` rows recomputed from its total savings
    (``simulated``: the columns that are simulated runs; the others are offline)."""
    wide = wide.drop(index=list(DERIVED_KPIS), errors="ignore")
    if "total_saving_km" not in wide.index:
        return wide
    offline = savings_of(wide, [str(c) for c in wide.columns if c not in simulated])
    for run, row in derived_rows(savings_of(wide, simulated), offline).items():
        for kpi, value in row.items():
            wide.loc[kpi, run] = value
    return wide


def bracket_record(table: pd.DataFrame, simulated: Collection[str]) -> dict[str, object]:
    """The bracket of a comparison table as ``rpbench run --json`` prints it: the best known schedule (run and
    saving, LB), U and U / LB (None where undefined)."""
    lb = best_known(savings_of(table, simulated))
    bound = savings_of(table, [BOUND]).get(BOUND)
    return {
        BEST_KNOWN_FIELD: lb.record() if lb else None,
        "upper_bound_km": bound,
        "bound_over_best_known": over(bound, lb.saving_km) if lb and bound is not None else None,
    }


def bracket_line(
    table: pd.DataFrame, simulated: Collection[str], text: Callable[[str, float], str], styles: Styles | None = None
) -> str | None:
    """The line under a comparison table: where OPT lies, ``OPT lies in [LB, U] = [999, 1,340] km (U / LB =
    1.34; best known schedule: Hindsight (clairvoyant))``; None without a simulated run (``text(kpi, value)``
    formats a number as the table does)."""
    lb = best_known(savings_of(table, simulated))
    if lb is None:
        return None
    who = f"best known schedule: {run_label(lb.run, styles)}"
    low = text("total_saving_km", lb.saving_km)
    if BOUND not in table.columns or "total_saving_km" not in table.index:
        return f"{BRACKET_PREFIX}>= LB = {low} km ({who}; no upper bound run, so no U)."
    bound = float(table.loc["total_saving_km", BOUND])
    width = over(bound, lb.saving_km)
    return (
        f"{BRACKET_PREFIX}lies in [LB, U] = [{low}, {text('total_saving_km', bound)}] km "
        f"(U / LB = {'/' if math.isnan(width) else f'{width:.2f}'}; {who})."
    )
