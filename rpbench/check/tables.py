"""``parent-tables``: a parent folder's table holds the rows recomputed from its children, value for value.

Shared by every parent kind (:mod:`.parents`: by_day.csv, summary.csv, sweep.csv; :mod:`.evaluation`:
units.csv, leaderboard.csv, paired.csv).  The comparison is vectorised: an evaluation of 70 units has tens of
thousands of rows, and the checker's cost should stay that of reading them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.check.core import KNOWN_KPIS, KPI_ATOL, KPI_RTOL, RunCheck, show
from rpbench.exceptions import ResultsError, one_line
from rpbench.results.layout import KPIS
from rpbench.results.legacy import current_names
from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.ratios import DERIVED_KPIS

TABLES_CHECK = "parent-tables"
#: The bound's matching statistics under their own names (rpbench.results.metrics).
MATCHING_KPIS = tuple(BOUND_MATCHING_KPIS.values())


def compare_table(fc: RunCheck, path: Path, expected: pd.DataFrame, keys: list[str], values: list[str]) -> None:
    """The table at ``path`` holds the rows of ``expected`` (by ``keys``) with the same ``values``."""
    if not path.is_file():
        fc.skip(TABLES_CHECK, f"the folder has no {path.name}")
        return
    try:
        found = current_names(results.read_csv(path))  # an older rpbench's KPI names read as today's
    except ResultsError as exc:
        fc.fail(TABLES_CHECK, one_line(exc))
        return
    if not set(keys + values) <= set(found.columns):
        fc.fail(TABLES_CHECK, f"{path.name} lacks column(s) of {', '.join(keys + values)}")
        return
    have, want = _keyed(found, keys, values), _keyed(expected, keys, values)
    if have.index.has_duplicates:
        fc.fail(TABLES_CHECK, f"{path.name}: a row repeats")
        return
    defined = want.drop(columns=["count", "point"], errors="ignore")  # a count or a sweep point is no value
    extra = set(have.index.difference(want.index))
    missing = want.index.difference(have.index)
    lost = set(missing[defined.loc[missing].notna().any(axis=1).to_numpy()])  # an undefined row loses nothing
    # Rows of KPIs this rpbench does not know, derived rows an older version rendered (an offline run's ratio,
    # the bound's matching statistics in a leaderboard) or derived KPIs it did not render at all: not compared,
    # and said so.
    written = {k[-1] for k in have.index}
    other = {k for k in extra if k[-1] not in KNOWN_KPIS or k[-1] in {*DERIVED_KPIS, *MATCHING_KPIS}}
    other |= {k for k in lost if k[-1] in DERIVED_KPIS and k[-1] not in written}
    if other:
        fc.skip(
            TABLES_CHECK,
            f"{path.name}: rows of {', '.join(sorted({k[-1] for k in other}))} not compared "
            "(rendered by another rpbench version)",
        )
    unknown, absent = sorted(extra - other), sorted(lost - other)
    if unknown or absent:
        fc.fail(
            TABLES_CHECK,
            f"{path.name}: rows {unknown[:3]} are not in the children's {KPIS}, rows {absent[:3]} are missing",
        )
        return
    _compare_values(fc, path.name, have, want, defined, values)
    fc.checked[path.stem] = len(want)


def _keyed(table: pd.DataFrame, keys: list[str], values: list[str]) -> pd.DataFrame:
    # an undated evaluation's day is empty, read back from a CSV as NaN
    text = {k: table[k].astype(object).where(table[k].notna(), "").astype(str) for k in keys}
    return table.assign(**text).set_index(keys)[values]


def _compare_values(
    fc: RunCheck, name: str, have: pd.DataFrame, want: pd.DataFrame, defined: pd.DataFrame, values: list[str]
) -> None:
    """Every value of the rows both tables hold, equal up to the KPI tolerance (NaN equal to NaN)."""
    common = want.index[want.index.isin(have.index)]
    w, h = want.loc[common], have.loc[common]
    kpi = pd.Series([k[-1] for k in common], index=common, dtype=object)
    undefined = (kpi.isin(DERIVED_KPIS) & defined.loc[common].isna().all(axis=1)).to_numpy()
    # an offline run's ratio, which an older rpbench rendered where today's derives none
    older = sorted(set(kpi[undefined & h[list(defined.columns)].notna().any(axis=1).to_numpy()]))
    for column in values:
        reported = pd.to_numeric(h[column], errors="coerce").to_numpy(dtype=float)
        text = np.isnan(reported) & h[column].notna().to_numpy()
        value = w[column].to_numpy(dtype=float)
        both_nan = np.isnan(reported) & np.isnan(value)
        close = np.isclose(reported, value, rtol=KPI_RTOL, atol=KPI_ATOL) | both_nan
        for k in np.flatnonzero(~undefined & (text | ~close)):
            fc.fail(
                TABLES_CHECK,
                f"{name}: {column} of {common[k]} is {show(h[column].iloc[k])}, the children's {KPIS} give "
                f"{float(value[k])!r}",
            )
    if older:
        fc.skip(
            TABLES_CHECK,
            f"{name}: values of {', '.join(older)} where today's rpbench derives none (an offline run's, rendered "
            "by an older rpbench) not compared",
        )
