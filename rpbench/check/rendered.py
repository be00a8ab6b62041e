"""Reading back what an evaluation's reports show: markdown tables, LaTeX table rows, a page's HTML tables,
list items and embedded figure data.

The checker compares these with their rendering from the checked tables (:mod:`.evaluation_report`) and
looks for every run in them (:mod:`.coverage`); reading them is kept apart so that both compare the same
cells.  Nothing here judges: an unparseable file reads as having no tables or no figure.
"""

from __future__ import annotations

import base64
import html
import json
import re
from typing import Any

import numpy as np

#: Where one markdown cell ends: a ``|`` not escaped (a label's own ``|`` is written ``\\|``).
_MD_BORDER = re.compile(r"(?<!\\)\|")
_HTML_TABLE = re.compile(r"<table[^>]*>(.*?)</table>", re.S)
_HTML_ROW = re.compile(r"<tr[^>]*>(.*?)</tr>", re.S)
_HTML_CELL = re.compile(r"<t[hd][^>]*>(.*?)</t[hd]>", re.S)
_HTML_ITEM = re.compile(r"<li[^>]*>(.*?)</li>", re.S)
_TAG = re.compile(r"<[^>]+>")
_PAGE_DATA = re.compile(r'<script type="application/json" id="rpbench-data">(.*?)</script>', re.S)
#: The headings after which a page shows its own links and figures, no longer its report.md (the figures it
#: draws in place of report.md's PNGs are no tables nor lists; the last heading is an older rpbench's).
PAGE_OWN_HEADINGS = ("Folders inside", "Figures (interactive)", "Leaderboard (interactive)")

Table = list[list[str]]


def markdown_tables(text: str) -> list[Table]:
    """Every table of a markdown text: its rows (the header first, the ``|---|`` line left out) as cell texts."""
    tables: list[Table] = []
    current: Table | None = None
    for line in text.splitlines():
        if not line.startswith("|"):
            current = None
            continue
        cells = [c.strip() for c in _MD_BORDER.split(line.strip().removeprefix("|").removesuffix("|"))]
        if current is None:
            current = []
            tables.append(current)
        if not set("".join(cells)) <= set("-: "):
            current.append(cells)
    return tables


def latex_rows(text: str) -> Table:
    """The rows of a booktabs table (the header first) as cell texts, rules and the environment left out."""
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line.endswith("\\\\") and not line.startswith("\\"):
            rows.append([c.strip() for c in re.split(r"(?<!\\)&", line.removesuffix("\\\\"))])
    return rows


def page_body(text: str) -> str:
    """The part of a page that shows its report.md (before the page's own links and figures)."""
    for heading in PAGE_OWN_HEADINGS:
        text = text.split(f">{heading}</h2>", 1)[0]
    return text


def html_tables(text: str) -> list[Table]:
    """Every HTML table of ``text``: rows of cell texts (tags stripped, entities read)."""
    return [
        [[_plain(cell) for cell in _HTML_CELL.findall(row)] for row in _HTML_ROW.findall(table)]
        for table in _HTML_TABLE.findall(text)
    ]


def html_items(text: str) -> list[str]:
    """The texts of every list item of ``text``."""
    return [_plain(item) for item in _HTML_ITEM.findall(text)]


def markdown_html(text: str) -> str:
    """A report's markdown as the pages render it (CommonMark with tables, no raw HTML)."""
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).enable("table").render(text)


def page_figure(text: str, ident: str) -> dict[str, Any] | None:
    """The Plotly figure ``ident`` a page embeds (its data decoded: typed arrays as lists); None when the page
    embeds no such figure or its data does not parse."""
    found = _PAGE_DATA.search(text)
    if found is None:
        return None
    try:
        figure = json.loads(found.group(1))["figures"][ident]
    except (ValueError, KeyError, TypeError):
        return None
    return decoded(figure) if isinstance(figure, dict) else None


def decoded(value: Any) -> Any:
    """Plotly JSON with its typed arrays (``{"dtype", "bdata", "shape"}``, base64) read as nested lists."""
    if isinstance(value, dict) and isinstance(value.get("bdata"), str) and isinstance(value.get("dtype"), str):
        try:
            array = np.frombuffer(base64.b64decode(value["bdata"]), dtype=np.dtype(value["dtype"]))
            shape = value.get("shape")
            if isinstance(shape, str):
                array = array.reshape([int(n) for n in shape.split(",")])
            return array.tolist()
        except (ValueError, TypeError):
            return None
    if isinstance(value, dict):
        return {k: decoded(v) for k, v in value.items()}
    if isinstance(value, list):
        return [decoded(v) for v in value]
    return value


def _plain(fragment: str) -> str:
    return " ".join(html.unescape(_TAG.sub("", fragment)).split())
