"""A multi-day, sweep or evaluation parent folder's own checks: ``manifest`` (every listed day, point or
unit folder is there, and no other), ``parent-tables`` (by_day.csv and summary.csv or sweep.csv, recomputed
from its children's KPIs, :mod:`.tables`) and an evaluation's own (:mod:`.evaluation`: its protocol, its
units against it, its tables, ranking, reports).

The children themselves are comparison folders, checked one by one by the entry point (:mod:`.tree`), in full
or as published light copies (:mod:`.light`).
"""

from __future__ import annotations

from pathlib import Path

from rpbench import results
from rpbench.check.core import FOLDER, FolderResult, RunCheck
from rpbench.check.evaluation import check_evaluation
from rpbench.check.tables import TABLES_CHECK, compare_table
from rpbench.exceptions import RpbenchError, one_line
from rpbench.results.layout import BY_DAY, META, RUNS, SUMMARY, SWEEP
from rpbench.results.parents import by_day_table, sweep_table


def listed_children(meta: dict) -> list[str] | None:
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
    found |= {p.name: p for p in light_children(parent)}
    listed = listed_children(meta)
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


def light_children(parent: Path) -> list[Path]:
    """The folders directly in ``parent`` that hold a meta.json but no runs: published light copies (or the
    remains of a deleted child, which its own check names)."""
    return sorted(p for p in parent.iterdir() if p.is_dir() and (p / META).is_file() and not (p / RUNS).is_dir())


def _check_parent_tables(fc: RunCheck, parent: Path, meta: dict) -> None:
    """by_day.csv and summary.csv (multi-day) or sweep.csv are the children's kpis.csv, reshaped and averaged;
    the children's own checks verify those.  An evaluation's own checks are :mod:`.evaluation`'s."""
    if meta["kind"] == "evaluate":
        check_evaluation(fc, parent, meta)
        return
    try:
        if meta["kind"] == "multi-day":
            table = by_day_table(parent)
            compare_table(fc, parent / BY_DAY, table, ["date", "run", "kpi"], ["value"])
            stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
            compare_table(
                fc, parent / SUMMARY, stats.reset_index(), ["run", "kpi"], ["mean", "std", "min", "max", "count"]
            )
        else:
            compare_table(fc, parent / SWEEP, sweep_table(parent), ["label", "run", "kpi"], ["point", "value"])
    except (RpbenchError, KeyError, ValueError, TypeError) as exc:
        fc.skip(
            TABLES_CHECK,
            f"the children's KPI tables cannot be gathered ({type(exc).__name__}: "
            f"{one_line(exc)}); their own checks say why",
        )
