"""Render the report of any results folder (comparison, multi-day or sweep) from its files alone, or combine
several comparison folders of one scenario into one comparison."""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path

from rpbench import files, results
from rpbench.exceptions import ResultsError
from rpbench.harness.multiday import write_multiday_report
from rpbench.harness.sweep import write_sweep_report
from rpbench.report.combine import combine, combined_markdown, write_combined
from rpbench.report.comparison import check_metrics, selected_markdown, write_report
from rpbench.report.evaluation import write_evaluation_report
from rpbench.report.html import write_html
from rpbench.report.html.bench import bench_tables, write_bench_folder
from rpbench.results import layout
from rpbench.results.layout import HEAVY, PARENT_KINDS, REPORT
from rpbench.results.read import load_kpis
from rpbench.results.runs import run_styles
from rpbench.spec import DEFAULT_FIGURE_FORMATS

#: A report's figures: PNG, and the vector copies beside each when asked for (:data:`rpbench.spec.FIGURE_FORMATS`).
FIGURE_SUFFIXES = (".png", *layout.VECTOR_SUFFIXES)
FIGURE_PATTERNS = tuple(f"*{s}" for s in FIGURE_SUFFIXES)


def render(
    folders: list[Path],
    metrics: list[str] | None = None,
    dest: Path | None = None,
    *,
    page: bool = False,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> tuple[str, list[Path]]:
    """Render the report of one folder, or combine several; return (markdown, written paths).

    One folder: its own report (comparison, multi-day or sweep), rewritten in it from its files, or
    with ``dest`` written into ``dest`` (the folder is then only read); ``page``: its ``report.html``
    too (:func:`rpbench.report.html.write_html`).  A ``rpbench replicate`` folder's report.md is
    written by the replication only: here it gets its page.  Several folders: comparison folders of
    one scenario combined into one comparison (:mod:`rpbench.report.combine`); nothing is written in
    them, and with ``dest`` the combined table and figure go there.  ``formats``: the figures' formats
    (:func:`rpbench.spec.figure_formats`); figures of other formats already there are left as they are.
    """
    metrics = check_metrics(metrics)
    for folder in folders:
        if not folder.is_dir():
            raise ResultsError(f"results folder {str(folder)!r} does not exist")
    if len(folders) > 1:
        text, paths = _render_combined(folders, metrics, dest, page=page, formats=formats)
        return files.printable(text), paths  # a folder name's non-UTF-8 bytes escaped, as in the files
    folder = folders[0]
    written = _render_one(folder, dest, page=page, formats=formats)
    if metrics is not None:
        return files.printable(_selected(folder, metrics)), [written]
    if written.suffix == ".html":
        return f"page written to {written}", [written]
    return files.printable(written.read_text(errors="surrogateescape")), [written]


def _render_one(folder: Path, dest: Path | None, *, page: bool, formats: Sequence[str]) -> Path:
    """Write one folder's report (and page) into it, or into ``dest``; returns the report's (or page's) path."""
    if page and not (folder / layout.META).is_file() and bench_tables(folder):
        # a folder of `rpbench bench --csv` tables: its page only (there is no report.md to render)
        return write_bench_folder(folder, dest)
    kind = results.read_meta(folder).get("kind", "comparison")
    if kind == "replication":
        if not page:
            raise ResultsError(
                f"{str(folder)!r} is a rpbench replicate folder: its report.md is written by the replication; "
                "--html renders its page"
            )
        write_html(folder, dest=dest)
        return folder / REPORT
    if kind not in PARENT_KINDS and not results.run_names(folder) and not (folder / "kpis.csv").is_file():
        # a published light copy keeps kpis.csv but not the event logs under runs/
        raise ResultsError(f"results folder {str(folder)!r} holds no runs (no runs/ and no kpis.csv)")
    if dest is None:
        written = _write(folder, kind, formats=formats)
        if page:
            write_html(folder)
        return written
    written = _write_elsewhere(folder, kind, dest, formats)
    if page:
        write_html(folder, folder.name, dest=dest)
    return written


def _selected(folder: Path, metrics: list[str]) -> str:
    """One folder's table of the KPIs ``metrics`` only (a parent folder's: where its report is)."""
    meta = results.read_meta(folder)
    if meta.get("kind", "comparison") != "comparison":
        block = f"## {folder.name}\n\nsee {folder / 'report.md'}\n"
    else:
        table = load_kpis(folder)
        table = table.loc[[m for m in metrics if m in table.index]]
        block = (
            f"## {folder.name}\n\n{meta['scenario']['label']}, preset `{meta['preset']['name']}`\n\n"
            + selected_markdown(table, run_styles(meta))
            + "\n"
        )
    return "# rpbench results\n\n" + block


def _render_combined(
    folders: list[Path], metrics: list[str] | None, dest: Path | None, *, page: bool, formats: Sequence[str]
) -> tuple[str, list[Path]]:
    """Several comparison folders as one comparison: its markdown, and with ``dest`` its table and figure
    written there.  The folders are only read: a page would be a page of one of them."""
    if page:
        raise ResultsError(
            "--html renders one folder's page: several folders combine into one markdown report; "
            "render each folder's page alone (rpbench report DIR --html)"
        )
    combined = combine(folders)
    written = [] if dest is None else write_combined(combined, dest, metrics, formats)
    return combined_markdown(combined, metrics, figures=dest is not None), written


def _write(folder: Path, kind: str, name: str | None = None, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS) -> Path:
    if kind == "multi-day":
        return write_multiday_report(folder, name, formats)
    if kind == "sweep":
        return write_sweep_report(folder, name, formats)
    if kind == "evaluate":
        return write_evaluation_report(folder, name, formats=formats)
    return write_report(folder, name, formats=formats)


def _write_elsewhere(folder: Path, kind: str, dest: Path, formats: Sequence[str]) -> Path:
    """The report of ``folder`` and its figures written into ``dest``, nothing written in ``folder``.

    A parent folder's report writer writes beside the files it reads, so it runs on a copy of the
    folder's tables (no event logs, inputs, reports nor figures) and only its report and figures move.
    """
    if kind not in PARENT_KINDS:
        return write_report(folder, folder.name, dest, formats=formats)
    with tempfile.TemporaryDirectory(dir=dest) as tmp:
        copy = Path(tmp) / folder.name
        shutil.copytree(folder, copy, ignore=shutil.ignore_patterns(*HEAVY, REPORT, *FIGURE_PATTERNS))
        _write(copy, kind, folder.name, formats)
        for path in copy.iterdir():
            if path.name == REPORT or path.suffix in FIGURE_SUFFIXES:
                shutil.move(path, dest / path.name)
    return dest / REPORT
