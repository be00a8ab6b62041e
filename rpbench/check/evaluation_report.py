"""``report`` and ``report-html`` of an evaluation: report.md, table.tex and report.html show the checked tables.

They are rendered again from the tables the checker recomputed from the units
(:func:`rpbench.report.evaluation.evaluation_report`, the page's figure by
:func:`rpbench.report.html.figures.leaderboard_bars`) and compared:

* report.md: its header (protocol, scenario, dates, sample, seeds, number of units, presets, rpbench version and
  commit, protocol digest, command), every table (the leaderboard, the paired tests) cell by cell and the
  figures it embeds; prose worded otherwise (another rpbench version) is listed as not compared;
* table.tex: whole;
* report.html: the list items (the header) and tables of the report.md it shows, and the data of its
  leaderboard figure (each metric's runs, means and intervals).

The figures drawn as PNG, SVG and PDF are renderings of leaderboard.csv and units.csv and are not compared.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench import results
from rpbench.check.core import RunCheck
from rpbench.check.rendered import (
    html_items,
    html_tables,
    markdown_html,
    markdown_tables,
    page_body,
    page_figure,
)
from rpbench.exceptions import RpbenchError, one_line
from rpbench.report.evaluation import board_metrics, evaluation_report
from rpbench.results.layout import REPORT, REPORT_HTML, TABLE_TEX
from rpbench.results.runs import run_styles

REPORT_CHECK, PAGE_CHECK = "report", "report-html"
#: The page's interactive leaderboard.
FIGURE = "fig-leaderboard"
#: Raw values are rendered from the same floats; a tolerance only for a page drawn from leaderboard.csv's text.
FIGURE_REL_TOL = 1e-12


def check_evaluation_report(
    fc: RunCheck,
    parent: Path,
    meta: dict,
    tables: tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame],
    runs: Sequence[str],
) -> None:
    """report.md, table.tex and report.html against their rendering from ``tables`` (units, leaderboard with
    its ranking, paired tests, as the checker recomputed them) and ``runs`` (the evaluation's)."""
    units, board, pairs = tables
    try:
        want = evaluation_report(parent, parent.name, board, pairs, units, runs)
        styles = run_styles(results.read_meta(parent / meta["children"][0]))
    except (RpbenchError, KeyError, ValueError, TypeError, IndexError) as exc:
        fc.skip(REPORT_CHECK, f"the reports cannot be rendered ({type(exc).__name__}: {one_line(exc)})")
        return
    _check_markdown(fc, parent / REPORT, want.markdown)
    _check_whole(fc, parent / TABLE_TEX, want.tex)
    _check_page(fc, parent / REPORT_HTML, want.markdown, board, list(meta["protocol"]["metrics"]), styles)


def _sections(text: str) -> tuple[list[str], list[str], list[str]]:
    """(the header: lines before the first section; the embedded figures; the prose) of a report."""
    lines = text.splitlines()
    first = next((i for i, line in enumerate(lines) if line.startswith("## ")), len(lines))
    rest = [line for line in lines[first:] if line.strip() and not line.startswith("|")]
    images = [line for line in rest if line.startswith("![")]
    return lines[:first], images, [line for line in rest if not line.startswith("![")]


def _check_markdown(fc: RunCheck, path: Path, want: str) -> None:
    if not path.is_file():
        fc.skip(REPORT_CHECK, f"the evaluation has no {path.name}")
        return
    have = path.read_text(encoding="utf-8", errors="replace")
    (head, images, prose), (want_head, want_images, want_prose) = _sections(have), _sections(want)
    if head != want_head:
        fc.fail(REPORT_CHECK, f"{path.name}'s header {_first_difference(head, want_head)}")
    if images != want_images:
        fc.fail(REPORT_CHECK, f"{path.name} embeds figures {_first_difference(images, want_images)}")
    _compare_tables(fc, REPORT_CHECK, path.name, markdown_tables(have), markdown_tables(want))
    differ = len(set(prose) ^ set(want_prose))
    if differ:
        fc.skip(REPORT_CHECK, f"{path.name}: {differ} line(s) of prose not compared (worded by another version)")
    fc.checked["report_lines"] = len(want.splitlines())


def _check_whole(fc: RunCheck, path: Path, want: str) -> None:
    if not path.is_file():
        fc.skip(REPORT_CHECK, f"the evaluation has no {path.name}")
        return
    have = path.read_text(encoding="utf-8", errors="replace")
    if have.splitlines() != want.splitlines():
        fc.fail(REPORT_CHECK, f"{path.name} {_first_difference(have.splitlines(), want.splitlines())}")


def _check_page(fc: RunCheck, path: Path, markdown: str, board: pd.DataFrame, metrics: list[str], styles: dict) -> None:
    if not path.is_file():
        fc.skip(PAGE_CHECK, f"the evaluation has no {path.name}")
        return
    text = path.read_text(encoding="utf-8", errors="replace")
    body, want = page_body(text), markdown_html(markdown)
    items, want_items = html_items(body), html_items(want)
    if items != want_items:
        fc.fail(PAGE_CHECK, f"{path.name}'s list {_first_difference(items, want_items)}")
    _compare_tables(fc, PAGE_CHECK, path.name, html_tables(body), html_tables(want))
    figure = page_figure(text, FIGURE)
    if figure is None or not isinstance(figure.get("data"), list):
        fc.fail(PAGE_CHECK, f"{path.name} embeds no leaderboard figure ({FIGURE})")
        return
    expected = _figure_data(board, metrics, styles)
    if len(figure["data"]) != len(expected):
        fc.fail(PAGE_CHECK, f"{path.name}'s leaderboard figure has {len(figure['data'])} traces, the units give "
                            f"{len(expected)}")  # fmt: skip
        return
    for have, want_trace in zip(figure["data"], expected, strict=True):
        for field in ("name", "visible", "x", "y", "customdata", ("error_y", "array"), ("error_y", "arrayminus")):
            if not _same(_at(have, field), _at(want_trace, field)):
                fc.fail(
                    PAGE_CHECK,
                    f"{path.name}'s leaderboard figure, trace {want_trace.get('name')!r}: {_name(field)} is "
                    f"{_short(_at(have, field))}, the units give {_short(_at(want_trace, field))}",
                )
                break
    fc.checked["page_traces"] = len(expected)


def _figure_data(board: pd.DataFrame, metrics: list[str], styles: dict) -> list[dict[str, Any]]:
    import plotly.io as pio

    from rpbench.check.rendered import decoded
    from rpbench.report.html.figures import leaderboard_bars

    figure = leaderboard_bars(board, board_metrics(metrics), styles)
    return decoded(json.loads(pio.to_json(figure, validate=False, engine="json")))["data"]


def _compare_tables(fc: RunCheck, check: str, name: str, have: list, want: list) -> None:
    if len(have) != len(want):
        fc.fail(check, f"{name} has {len(have)} table(s), the units render {len(want)}")
        return
    for have_rows, want_rows in zip(have, want, strict=True):
        if have_rows != want_rows:
            fc.fail(check, f"{name}'s table {' | '.join(want_rows[0][:2])} ...: {_first_row(have_rows, want_rows)}")


def _first_row(have: list[list[str]], want: list[list[str]]) -> str:
    for k in range(max(len(have), len(want))):
        a = have[k] if k < len(have) else None
        b = want[k] if k < len(want) else None
        if a != b:
            return f"row {k} shows {_row(a)}; the units render {_row(b)}"
    return "rows differ"


def _first_difference(have: list[str], want: list[str]) -> str:
    for k in range(max(len(have), len(want))):
        a = have[k] if k < len(have) else None
        b = want[k] if k < len(want) else None
        if a != b:
            return f"reads {a!r} where the units render {b!r}"
    return "differs"


def _row(cells: list[str] | None) -> str:
    return "nothing" if cells is None else " | ".join(cells)


def _at(trace: dict, field: str | tuple[str, str]) -> Any:
    if isinstance(field, str):
        return trace.get(field)
    inner = trace.get(field[0])
    return inner.get(field[1]) if isinstance(inner, dict) else None


def _name(field: str | tuple[str, str]) -> str:
    return field if isinstance(field, str) else ".".join(field)


def _same(a: Any, b: Any) -> bool:
    """Equal, numbers within :data:`FIGURE_REL_TOL` (NaN equal to NaN, as JSON's null)."""
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and not isinstance(b, bool):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return math.isclose(a, b, rel_tol=FIGURE_REL_TOL, abs_tol=1e-12)
    return a == b


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 120 else text[:117] + "..."
