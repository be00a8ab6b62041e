"""Render the report of any results folder (comparison, multi-day or sweep) from its files alone."""

from __future__ import annotations

from pathlib import Path

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.harness.multiday import write_multiday_report
from rpbench.harness.sweep import write_sweep_report
from rpbench.results.report import check_metrics, load_kpis, selected_markdown, write_report


def render(folders: list[Path], metrics: list[str] | None = None) -> tuple[str, list[Path]]:
    """Re-render the report of each folder from its files; return (markdown, written report paths).

    One folder: its own report (comparison, multi-day or sweep).  Several
    comparison folders: a combined table with one column group per folder.
    """
    metrics = check_metrics(metrics)
    written = []
    for folder in folders:
        if not folder.is_dir():
            raise ResultsError(f"results folder {str(folder)!r} does not exist")
        kind = results.read_meta(folder).get("kind", "comparison")
        if kind == "multi-day":
            written.append(write_multiday_report(folder))
        elif kind == "sweep":
            written.append(write_sweep_report(folder))
        else:
            # a published light copy keeps kpis.csv but not the event logs under runs/
            if not results.run_names(folder) and not (folder / "kpis.csv").is_file():
                raise ResultsError(f"results folder {str(folder)!r} holds no runs (no runs/ and no kpis.csv)")
            written.append(write_report(folder))
    if len(folders) == 1 and metrics is None:
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
