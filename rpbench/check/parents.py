"""A multi-day, sweep or evaluation parent folder's own checks: ``manifest`` (every listed day, point or
unit folder is there), ``parent-tables`` (by_day.csv and summary.csv, sweep.csv, or an evaluation's
units.csv, leaderboard.csv and paired.csv, recomputed from its children's KPIs) and an evaluation's
``ranking`` (:mod:`.ranking`).

The children themselves are comparison folders, checked one by one by the entry points.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.check.core import FOLDER, KNOWN_KPIS, FolderResult, RunCheck, as_number, same, show
from rpbench.check.ranking import check_ranking
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.report.evaluation import tables as evaluation_tables
from rpbench.results.layout import BY_DAY, KPIS, LEADERBOARD, META, PAIRED, SUMMARY, SWEEP, UNITS
from rpbench.results.legacy import current_names
from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.parents import by_day_table, sweep_table
from rpbench.results.ratios import DERIVED_KPIS

#: The bound's matching statistics under their own names (rpbench.results.metrics).
MATCHING_KPIS = tuple(BOUND_MATCHING_KPIS.values())


def _listed_children(meta: dict) -> list[str] | None:
    """The child folders a parent's meta.json lists: ``children`` (recorded since rpbench writes it), else the
    multi-day ``dates`` or the sweep points' labels (the folders are named after them); None: no list."""
    for listed in (
        meta.get("children"),
        meta.get("dates") if meta.get("kind") == "multi-day" else None,
        [p.get("label") for p in meta.get("points", []) if isinstance(p, dict)]
        if meta.get("kind") == "sweep" and isinstance(meta.get("points"), list)
        else None,
    ):
        if isinstance(listed, list) and listed and all(isinstance(x, str) for x in listed):
            return listed
    return None


def check_parent(parent: Path, meta: dict) -> tuple[FolderResult, list[Path]]:
    """A multi-day or sweep parent: every listed child folder is there (a deleted day or point fails
    ``manifest``), and its summary tables are its children's KPIs.  Returns the children to check."""
    fc = RunCheck(FOLDER)
    what = {"multi-day": "day", "evaluate": "evaluation unit"}.get(meta["kind"], "sweep point")
    found = {p.relative_to(parent).as_posix(): p for p in results.run_folders(parent) if p != parent}
    listed = _listed_children(meta)
    if listed is None:
        fc.skip("manifest", f"{META} lists no {what} folders")
        listed = []
    for name in listed:
        if not (parent / name).is_dir():
            fc.fail("manifest", f"{what} folder {name}/ listed in {META} is missing (deleted?)")
    for name in sorted(set(found) - set(listed)):
        if listed:
            fc.fail("manifest", f"{name}/ is not a {what} folder {META} lists")
    fc.checked["children"] = len(listed)
    _check_parent_tables(fc, parent, meta)
    children = sorted(set(found.values()) | {parent / name for name in listed if (parent / name).is_dir()})
    return FolderResult(str(parent), folder_check=fc), children


def _check_parent_tables(fc: RunCheck, parent: Path, meta: dict) -> None:
    """by_day.csv and summary.csv (multi-day) or sweep.csv are the children's kpis.csv, reshaped and averaged;
    the children's own checks verify those."""
    try:
        if meta["kind"] == "evaluate":
            units, board, pairs = evaluation_tables(parent)
            _compare_table(fc, parent / UNITS, units, ["day", "seed", "run", "kpi"], ["value"])
            stats = ["mean", "ci_low", "ci_high", "days", "seeds"]
            _compare_table(fc, parent / LEADERBOARD, board, ["run", "kpi"], stats)
            check_ranking(fc, parent / LEADERBOARD, board)
            tests = ["mean_diff", "ci_low", "ci_high", "wilcoxon_p", "days_a_above", "days_a_below", "days_tied"]
            _compare_table(fc, parent / PAIRED, pairs, ["a", "b", "kpi"], tests)
        elif meta["kind"] == "multi-day":
            table = by_day_table(parent)
            _compare_table(fc, parent / BY_DAY, table, ["date", "run", "kpi"], ["value"])
            stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
            _compare_table(
                fc, parent / SUMMARY, stats.reset_index(), ["run", "kpi"], ["mean", "std", "min", "max", "count"]
            )
        else:
            _compare_table(fc, parent / SWEEP, sweep_table(parent), ["label", "run", "kpi"], ["point", "value"])
    except (RpbenchError, KeyError, ValueError, TypeError) as exc:
        fc.skip(
            "parent-tables",
            f"the children's KPI tables cannot be gathered ({type(exc).__name__}: "
            f"{one_line(exc)}); their own checks say why",
        )


def _compare_table(fc: RunCheck, path: Path, expected: pd.DataFrame, keys: list[str], values: list[str]) -> None:
    """The table at ``path`` holds the rows of ``expected`` (by ``keys``) with the same ``values``."""
    if not path.is_file():
        fc.skip("parent-tables", f"the folder has no {path.name}")
        return
    try:
        found = current_names(results.read_csv(path))  # an older rpbench's KPI names read as today's
    except ResultsError as exc:
        fc.fail("parent-tables", one_line(exc))
        return
    if not set(keys + values) <= set(found.columns):
        fc.fail("parent-tables", f"{path.name} lacks column(s) of {', '.join(keys + values)}")
        return

    def keyed(table: pd.DataFrame) -> pd.DataFrame:
        # an undated evaluation's day is empty, read back from a CSV as NaN
        text = {k: table[k].astype(object).where(table[k].notna(), "").astype(str) for k in keys}
        return table.assign(**text).set_index(keys)[values]

    have, want = keyed(found), keyed(expected)
    if have.index.has_duplicates:
        fc.fail("parent-tables", f"{path.name}: a row repeats")
        return
    extra, lost = set(have.index) - set(want.index), set(want.index) - set(have.index)
    defined = want.drop(columns=["count", "point"], errors="ignore")  # a count or a sweep point is no value
    lost = {k for k in lost if defined.loc[[k]].notna().to_numpy().any()}  # an undefined row loses nothing
    # Rows of KPIs this rpbench does not know, derived rows an older version rendered (an offline run's ratio,
    # the bound's matching statistics in a leaderboard) or derived KPIs it did not render at all: not compared,
    # and said so.
    written = {k[-1] for k in have.index}
    other = {k for k in extra if k[-1] not in KNOWN_KPIS or k[-1] in {*DERIVED_KPIS, *MATCHING_KPIS}}
    other |= {k for k in lost if k[-1] in DERIVED_KPIS and k[-1] not in written}
    if other:
        fc.skip(
            "parent-tables",
            f"{path.name}: rows of {', '.join(sorted({k[-1] for k in other}))} not compared "
            "(rendered by another rpbench version)",
        )
    unknown, absent = sorted(extra - other), sorted(lost - other)
    if unknown or absent:
        fc.fail(
            "parent-tables",
            f"{path.name}: rows {unknown[:3]} are not in the children's {KPIS}, rows {absent[:3]} are missing",
        )
        return
    older = set()
    for key in want.index:
        if key not in have.index:
            continue  # undefined in the children: nothing to compare
        if key[-1] in DERIVED_KPIS and defined.loc[key].isna().all():
            if have.loc[key, list(defined.columns)].notna().any():
                older.add(key[-1])  # an offline run's ratio, which an older rpbench rendered
            continue
        for column in values:
            value = want.loc[key, column]
            rep = as_number(have.loc[key, column])
            if rep is None or not same(rep, float(value)):
                fc.fail(
                    "parent-tables",
                    f"{path.name}: {column} of {key} is {show(have.loc[key, column])}, the "
                    f"children's {KPIS} give {float(value)!r}",
                )
    if older:
        fc.skip(
            "parent-tables",
            f"{path.name}: values of {', '.join(sorted(older))} where today's rpbench derives none (an offline "
            "run's, rendered by an older rpbench) not compared",
        )
    fc.checked[path.stem] = len(want)
