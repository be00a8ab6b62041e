"""``rpbench check`` of any folder: a comparison (or its published light copy), a parent (multi-day, sweep,
evaluation: its own tables, then each child, in full or as a published light copy), a replication or a
``rpbench bench`` folder; the dispatch sits above the checkers it calls, so that a replication's check can
check its engines' folders as comparisons (:func:`.verify.check_results`)."""

from __future__ import annotations

from pathlib import Path

from rpbench import results
from rpbench.check.bench import KIND as BENCH_KIND
from rpbench.check.bench import check_bench
from rpbench.check.core import FolderResult
from rpbench.check.light import check_light_child, is_light, read_light_record
from rpbench.check.parents import check_parent, listed_children
from rpbench.check.replication import check_replication
from rpbench.check.verify import check_results
from rpbench.exceptions import RpbenchError, one_line
from rpbench.results.layout import META, PARENT_KINDS, RUNS


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
        assert parent.folder_check is not None
        record = read_light_record(parent.folder_check, meta, listed_children(meta) or [])
        return [parent] + _check_children(path, children, record)
    return [_check_run_folder(folder) for folder in results.run_folders(path)]


def _check_run_folder(folder: Path) -> FolderResult:
    """A comparison folder in full, or, published alone as a light copy, for what the copy keeps."""
    if is_light(folder):
        return check_light_child(folder, folder.name, None, lone=True)
    return check_results(folder)


def _check_children(parent: Path, children: list[Path], record) -> list[FolderResult]:
    """Each child in full when it holds its runs; as a light copy when the parent records one (a file missing
    then fails) or, without a record, when it has the verdict a publish writes (an older light copy)."""
    full = any((child / RUNS).is_dir() for child in children)
    out = []
    for child in children:
        name = child.relative_to(parent).as_posix()
        if (child / RUNS).is_dir():
            out.append(check_results(child))
        elif record is not None:
            out.append(check_light_child(child, name, record))
        elif is_light(child):
            out.append(check_light_child(child, name, None, among_full=full))
        else:
            out.append(check_results(child))
    return out
