"""Labels a user or plug-in chose are escaped where they are written into tables: markdown (``|``), LaTeX,
HTML and Plotly text; the checker's report check reads escaped cells."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
from plugin_helpers import forget

from rpbench.check.kpis import _metric_tables
from rpbench.cli import main
from rpbench.report.comparison import markdown_table, selected_markdown
from rpbench.report.html.figures import plotly_text
from rpbench.report.tables import latex_escape, latex_table
from rpbench.results.runs import markdown_cell

LABEL = "A|B <b>&\nnew line"
MODULE = f"""
from rpbench.strategies.myopic import MyopicBatch


class Piped(MyopicBatch):
    name = "piped"
    label = {LABEL!r}
"""


def cells(line: str) -> list[str]:
    """A markdown table row's cells, split where GitHub splits them (at a ``|`` not escaped)."""
    return re.split(r"(?<!\\)\|", line.strip().removeprefix("|").removesuffix("|"))


def table() -> pd.DataFrame:
    return pd.DataFrame({"np": [0.5, 1.0], "piped": [0.7, 2.0]}, index=["response_rate", "total_saving_km"])


def test_markdown_cell_escapes_pipes_and_line_breaks():
    assert markdown_cell(LABEL) == "A\\|B <b>& new line"
    assert markdown_cell("plain") == "plain"


@pytest.mark.parametrize("render", [markdown_table, selected_markdown])
def test_a_label_with_a_pipe_keeps_the_column_count(render):
    text = render(table(), styles={"piped": (LABEL, None)})
    lines = text.splitlines()
    assert all(len(cells(line)) == 3 for line in lines), text
    assert "A\\|B" in lines[0]


def test_latex_escapes_every_special_of_a_label():
    assert latex_escape("a|b<c>&_\nd") == r"a\textbar{}b\textless{}c\textgreater{}\&\_ d"
    tex = latex_table(table(), ["response_rate"], lambda k, v: f"{v:.2f}", caption="x", styles={"piped": (LABEL, None)})
    head = next(line for line in tex.splitlines() if line.startswith("Metric"))
    assert head.count("&") - head.count(r"\&") == 2  # three columns


def test_plotly_text_shows_markup_as_written():
    assert plotly_text("A <b>&") == "A &lt;b&gt;&amp;"


def test_the_checker_reads_escaped_cells():
    found = _metric_tables("| Metric | NP | A\\|B |\n|---|---:|---:|\n| Response rate | 0.50 | 0.70 |\n")
    assert found == [[("Response rate", ["0.50", "0.70"])]]


def test_a_plugin_label_with_a_pipe_renders_and_checks(capsys, tmp_path, monkeypatch):
    (tmp_path / "pipedmod.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    try:
        argv = ["run", "--scenario", "toy", "--sample", "0.1", "--strategies", "np,pipedmod:Piped"]
        assert main([*argv, "--no-progress", "--out", str(out)]) == 0
    finally:
        forget("pipedmod")
    capsys.readouterr()
    report = (out / "report.md").read_text()
    rows = [line for line in report.splitlines() if line.startswith("| ")]
    head = next(line for line in rows if line.startswith("| Metric |"))
    assert cells(head)[2].strip() == "A\\|B <b>& new line"
    table_rows = rows[: rows.index(head) + 10]
    assert {len(cells(line)) for line in table_rows if not line.startswith("|-")} == {3}
    page = (out / "report.html").read_text()
    markup = re.sub(r'<script type="application/json" id="rpbench-data">.*?</script>', "", page, flags=re.S)
    assert "A|B &lt;b&gt;&amp;" in markup and "<b>&" not in markup  # text, never markup (data is JSON)
    assert main(["check", str(out)]) == 0
    checked, _ = capsys.readouterr()
    assert "report_tables 1" in checked
    # the header, and the line under the table naming the best known schedule
    assert Path(out / "table.tex").read_text().count(r"A\textbar{}B") == 2
