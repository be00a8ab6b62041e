"""The comparison table for papers: LaTeX with the report's numbers, CSV with the raw values."""

from __future__ import annotations

import pandas as pd
import pytest

from rpbench.harness.comparison import run_comparison
from rpbench.report.comparison import fmt, markdown_table, table_rows
from rpbench.report.tables import latex_escape, latex_table
from rpbench.results.read import load_kpis
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


def test_latex_escapes_what_latex_would_read():
    assert latex_escape("FL-no_delay 5% & $x #1 {a} ~^\\") == (
        r"FL-no\_delay 5\% \& \$x \#1 \{a\} \textasciitilde{}\textasciicircum{}\textbackslash{}"
    )


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=4), ["mb", "fl-nd", "bound"], formats=("svg", "pdf"))
    return run_comparison(spec, tmp_path_factory.mktemp("tables") / "toy", progress=False).folder


def test_the_latex_table_prints_what_report_md_prints(folder):
    tex = (folder / "table.tex").read_text()
    assert "\\toprule" in tex and "\\bottomrule" in tex and "FL-no\\_delay" in tex
    body = [line.removesuffix(" \\\\").split(" & ") for line in tex.splitlines() if line.endswith("\\\\")][1:]
    md = [line.strip("| ").split(" | ") for line in markdown_table(load_kpis(folder)).splitlines()[2:]]
    assert [row[1:] for row in body] == [row[1:] for row in md]
    table = load_kpis(folder)
    marked = latex_table(table, table_rows(table), fmt, caption="c", unproven={"mb": "stopped"})
    assert "MB$^{*}$ & FL-no\\_delay" in marked  # an unproven run's column is marked, as in report.md


def test_the_csv_table_holds_the_raw_values(folder):
    csv = pd.read_csv(folder / "table.csv").set_index("kpi")
    tidy = pd.read_csv(folder / "kpis.csv").set_index(["run", "kpi"])["value"]
    assert list(csv.columns) == ["metric", "mb", "fl-nd", "bound"]
    assert csv.loc["total_saving_km", "mb"] == pytest.approx(tidy[("mb", "total_saving_km")], rel=1e-15)
    assert pd.isna(csv.loc["response_rate", "bound"])


def test_every_figure_has_the_vector_copies_asked_for(folder):
    for stem in ("kpis", "timeline"):
        assert (folder / f"{stem}.svg").read_text().lstrip().startswith("<?xml")
        assert (folder / f"{stem}.pdf").read_bytes()[:5] == b"%PDF-"
