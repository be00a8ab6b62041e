"""``rpbench check`` of any folder: a comparison, a parent (multi-day, sweep, evaluation: its own tables,
then each child), a replication or a ``rpbench bench`` folder; the dispatch sits above the checkers it
calls, so that a replication's check can check its engines' folders as comparisons
(:func:`.verify.check_results`)."""

from __future__ import annotations

from pathlib import Path

from rpbench import results
from rpbench.check.bench import KIND as BENCH_KIND
from rpbench.check.bench import check_bench
from rpbench.check.core import FolderResult
from rpbench.check.parents import check_parent
from rpbench.check.replication import check_replication
from rpbench.check.verify import check_results
from rpbench.exceptions import RpbenchError, one_line
from rpbench.results.layout import META, PARENT_KINDS


def check_tree(path: str | Path) -> list[FolderResult]:
    """Check a results folder, or a multi-day / sweep parent (its own files, then every child folder);
    an unreadable folder is a :class:`FolderResult` with ``error`` set, never an exception."""
    path = Path(path)
    if not path.is_dir():
        return [FolderResult(str(path), error=f"results folder {str(path)!r} does not exist")]
    meta = None
    if (path / META).exists():
        try:
            meta = results.read_meta(path)
        except RpbenchError as exc:
            return [FolderResult(str(path), error=one_line(exc))]
    if meta is not None and meta.get("kind") == "replication":
        return [check_replication(path)]
    if meta is not None and meta.get("kind") == BENCH_KIND:
        return [check_bench(path)]
    if meta is not None and meta.get("kind") in PARENT_KINDS:
        parent, children = check_parent(path, meta)
        return [parent] + [check_results(child) for child in children]
    return [check_results(folder) for folder in results.run_folders(path)]
