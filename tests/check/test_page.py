"""report.html's comparison table edited alone — a printed number, a raw value, a cell removed: ``report-html``."""

from __future__ import annotations

import re

from check.tamper import assert_fails, violations


def edit_page(folder, pattern: str, replacement: str) -> None:
    path = folder / "report.html"
    text = path.read_text()
    edited, n = re.subn(pattern, replacement, text, count=1)
    assert n == 1, pattern
    path.write_text(edited)


CELL = r'(data-run="mb" data-kpi="total_saving_km" data-value=")([^"]*)(">)([^<]*)(<)'


def test_the_page_of_a_run_passes(folder):
    assert "report-html" not in violations(folder)


def test_a_printed_number_edited_fails(folder):
    edit_page(folder, CELL, r"\g<1>\g<2>\g<3>999.9\g<5>")
    assert_fails(folder, "report-html", "report.html shows total_saving_km of mb: 999.9")


def test_a_raw_value_edited_fails(folder):
    edit_page(folder, CELL, r"\g<1>12345.0\g<3>\g<4>\g<5>")
    assert_fails(folder, "report-html", "(12345.0)")


def test_a_cell_removed_fails(folder):
    edit_page(folder, r'<td class="num" data-run="mb" data-kpi="total_saving_km"[^>]*>[^<]*</td>', "")
    assert_fails(folder, "report-html", "lacks 1 cells")


def test_a_page_without_its_table_fails(folder):
    edit_page(folder, r'id="comparison-table"', 'id="something-else"')
    assert_fails(folder, "report-html", "has no comparison table")
