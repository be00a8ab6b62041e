"""report.html of each kind of folder: written by the runs, its table the folder's kpis.csv."""

from __future__ import annotations

import html
import json
import re
import shutil

import pandas as pd
import pytest

from rpbench import results
from rpbench.harness.publish import publish
from rpbench.harness.render import render
from rpbench.report.html import write_html
from rpbench.results.read import load_kpis


def table_cells(page: str) -> dict[tuple[str, str], str]:
    """(run, kpi) -> raw value of the comparison table's cells."""
    table = page.split('id="comparison-table"')[1].split("</table>")[0]
    cells = re.findall(r'data-run="([^"]*)" data-kpi="([^"]*)" data-value="([^"]*)"', table)
    return {(html.unescape(r), k): v for r, k, v in cells}


def test_a_run_writes_its_page_whose_table_is_kpis_csv(toy_run):
    page = (toy_run / "report.html").read_text()
    cells = table_cells(page)
    wide = load_kpis(toy_run)
    tidy = results.read_csv(toy_run / "kpis.csv").set_index(["run", "kpi"])["value"]
    checked = 0
    for (run, kpi), raw in cells.items():
        expected = wide.loc[kpi, run]
        if (run, kpi) in tidy.index:
            expected = tidy[(run, kpi)]
            checked += 1
        assert (raw == "") == pd.isna(expected)
        if raw:
            assert float(raw) == pytest.approx(float(expected), rel=1e-12, abs=1e-12)
    assert checked >= 20 and ("bound", "competitive_ratio_bound") in cells
    data = json.loads(page.split('id="rpbench-data">')[1].split("</script>")[0].replace("<\\/", "</"))
    assert set(data["figures"]) == {"fig-kpis", "fig-timeline", "fig-rounds"} and data["map"]["runs"]


def test_a_page_is_rewritten_identically_from_the_files(toy_run, tmp_path):
    before = (toy_run / "report.html").read_bytes()
    write_html(toy_run, name=toy_run.name, dest=tmp_path)
    assert (tmp_path / "report.html").read_bytes() == before


def test_a_published_copy_keeps_the_map(toy_run, tmp_path):
    out = publish(toy_run, tmp_path / "published")
    page = (out / "report.html").read_text()
    assert "partial" not in page.split("</title>")[0]  # written under a temporary name, titled with its own
    assert '"map":{' in page and "published light copy" in page
    render([out], page=True)  # re-rendered from the light copy: the map cannot be drawn, and it says why
    again = (out / "report.html").read_text()
    assert '"map":null' in again and "light copy leaves out" in again


def test_report_html_flag_and_replicate_folders(toy_run, tmp_path, capsys):
    from rpbench.cli import main

    copy = tmp_path / "copy"
    shutil.copytree(toy_run, copy)
    (copy / "report.html").unlink()
    assert main(["report", str(copy)]) == 0 and not (copy / "report.html").exists()
    assert main(["report", str(copy), "--html"]) == 0 and (copy / "report.html").is_file()
    out = tmp_path / "elsewhere.md"
    assert main(["report", str(copy), "--html", "--out", str(out)]) == 0
    assert (tmp_path / "elsewhere-report.html").is_file()
