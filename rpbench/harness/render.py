"""Render the report of any results folder (comparison, multi-day or sweep) from its files alone."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.harness.multiday import write_multiday_report
from rpbench.harness.sweep import write_sweep_report
from rpbench.results import layout
from rpbench.results.evaluation import write_evaluation_report
from rpbench.results.html import write_html
from rpbench.results.html.bench import bench_tables, write_bench_folder
from rpbench.results.layout import HEAVY, REPORT
from rpbench.results.report import check_metrics, load_kpis, selected_markdown, write_report

#: A report's figures: PNG, and the vector copies beside each.
FIGURE_SUFFIXES = (".png", *layout.VECTOR_SUFFIXES)
FIGURE_PATTERNS = tuple(f"*{s}" for s in FIGURE_SUFFIXES)
#: Folder kinds whose report is written by their own harness module (all others are comparisons).
PARENT_KINDS = ("multi-day", "sweep", "evaluate")


def render(
    folders: list[Path], metrics: list[str] | None = None, dest: Path | None = None, *, page: bool = False
) -> tuple[str, list[Path]]:
    """Re-render the report of each folder from its files; return (markdown, written report paths).

    One folder: its own report (comparison, multi-day or sweep).  Several
    comparison folders: a combined table with one column group per folder.
    Each folder's report and figures are rewritten in it; with ``dest`` the
    folders are only read: one folder's report and figures go to ``dest``,
    several folders' combined table is only returned.  ``page``: each folder's
    ``report.html`` too (:func:`rpbench.results.html.write_html`), beside its
    report.  A ``rpbench replicate`` folder's report.md is written by the
    replication only: here it gets its page.
    """
    metrics = check_metrics(metrics)
    written = []
    for folder in folders:
        if not folder.is_dir():
            raise ResultsError(f"results folder {str(folder)!r} does not exist")
        if page and not (folder / layout.META).is_file() and bench_tables(folder):
            # a folder of `rpbench bench --csv` tables: its page only (there is no report.md to render)
            written.append(write_bench_folder(folder, dest))
            continue
        kind = results.read_meta(folder).get("kind", "comparison")
        if kind == "replication":
            if not page:
                raise ResultsError(
                    f"{str(folder)!r} is a rpbench replicate folder: its report.md is written by the replication; "
                    "--html renders its page"
                )
            if dest is None or len(folders) == 1:
                write_html(folder, dest=dest)
                written.append(folder / REPORT)
            continue
        if kind not in PARENT_KINDS and not results.run_names(folder) and not (folder / "kpis.csv").is_file():
            # a published light copy keeps kpis.csv but not the event logs under runs/
            raise ResultsError(f"results folder {str(folder)!r} holds no runs (no runs/ and no kpis.csv)")
        if dest is None:
            written.append(_write(folder, kind))
            if page:
                write_html(folder)
        elif len(folders) == 1:
            written.append(_write_elsewhere(folder, kind, dest))
            if page:
                write_html(folder, folder.name, dest=dest)
    if len(folders) == 1 and metrics is None:
        if written[0].suffix == ".html":
            return f"page written to {written[0]}", written
        return written[0].read_text(), written
    blocks = []
    for folder in folders:
        meta = results.read_meta(folder)
        if meta.get("kind", "comparison") != "comparison":
            blocks.append(f"## {folder.name}\n\nsee {folder / 'report.md'}\n")
            continue
        table = load_kpis(folder)
        if metrics is not None:
            table = table.loc[[m for m in metrics if m in table.index]]
        blocks.append(
            f"## {folder.name}\n\n{meta['scenario']['label']}, preset `{meta['preset']['name']}`\n\n"
            + selected_markdown(table)
            + "\n"
        )
    return "# rpbench results\n\n" + "\n".join(blocks), written


def _write(folder: Path, kind: str, name: str | None = None) -> Path:
    if kind == "multi-day":
        return write_multiday_report(folder, name)
    if kind == "sweep":
        return write_sweep_report(folder, name)
    if kind == "evaluate":
        return write_evaluation_report(folder, name)
    return write_report(folder, name)


def _write_elsewhere(folder: Path, kind: str, dest: Path) -> Path:
    """The report of ``folder`` and its figures written into ``dest``, nothing written in ``folder``.

    A parent folder's report writer writes beside the files it reads, so it runs on a copy of the
    folder's tables (no event logs, inputs, reports nor figures) and only its report and figures move.
    """
    if kind not in PARENT_KINDS:
        return write_report(folder, folder.name, dest)
    with tempfile.TemporaryDirectory(dir=dest) as tmp:
        copy = Path(tmp) / folder.name
        shutil.copytree(folder, copy, ignore=shutil.ignore_patterns(*HEAVY, REPORT, *FIGURE_PATTERNS))
        _write(copy, kind, folder.name)
        for path in copy.iterdir():
            if path.name == REPORT or path.suffix in FIGURE_SUFFIXES:
                shutil.move(path, dest / path.name)
    return dest / REPORT
