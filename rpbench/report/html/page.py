"""One self-contained HTML page: text, tables and Plotly figures, with the plotting library embedded once.

A :class:`Page` collects blocks in order (headings, paragraphs, tables, figure slots, the map) and renders
to one string: no ``http(s)`` source, link or font, so the file opens from anywhere, offline, alone.
Figures are stored as Plotly JSON and drawn by ``page.js`` while the page loads; the page's root
element says ``data-rpbench="ready"`` when every figure is drawn (``"error"`` and a message if not).
"""

from __future__ import annotations

import html
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rpbench.report.html import assets

#: Plotly's options for every figure: no logo, no "edit in the cloud", resize with the window.
PLOT_CONFIG = {"displaylogo": False, "responsive": True, "showLink": False, "showSendToCloud": False}


@dataclass(frozen=True)
class Cell:
    """A table cell: the text shown, and ``data-*`` attributes (raw values for scripts and tests)."""

    text: str
    data: Mapping[str, str] = field(default_factory=dict)
    numeric: bool = False


def _attrs(data: Mapping[str, str]) -> str:
    return "".join(f' data-{k}="{html.escape(str(v), quote=True)}"' for k, v in data.items())


@dataclass
class Page:
    """An HTML page under construction (blocks in order; figures by the id of their slot)."""

    title: str
    blocks: list[str] = field(default_factory=list)
    figures: dict[str, Any] = field(default_factory=dict)
    map: dict[str, Any] | None = None

    def heading(self, text: str, level: int = 2, anchor: str | None = None) -> None:
        ident = f' id="{html.escape(anchor)}"' if anchor else ""
        self.blocks.append(f"<h{level}{ident}>{html.escape(text)}</h{level}>")

    def paragraph(self, text: str, css: str | None = None) -> None:
        """A paragraph of plain text (escaped)."""
        self.markup(f"<p{_class(css)}>{html.escape(text)}</p>")

    def markup(self, fragment: str) -> None:
        """A fragment of HTML built by this package (its text already escaped)."""
        self.blocks.append(fragment)

    def bullets(self, items: Iterable[str]) -> None:
        self.markup("<ul>" + "".join(f"<li>{html.escape(i)}</li>" for i in items) + "</ul>")

    def code(self, text: str) -> None:
        self.markup(f"<pre><code>{html.escape(text)}</code></pre>")

    def table(
        self,
        head: Sequence[str],
        rows: Iterable[Sequence[Cell | str]],
        *,
        ident: str | None = None,
        caption: str | None = None,
    ) -> None:
        """A table; the first column is a row header, cells marked numeric are right-aligned."""
        ident_attr = f' id="{html.escape(ident)}"' if ident else ""
        out = [f'<div class="scroll"><table{ident_attr}>']
        if caption:
            out.append(f"<caption>{html.escape(caption)}</caption>")
        out.append("<thead><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr></thead><tbody>")
        for row in rows:
            cells = []
            for i, cell in enumerate(row):
                c = cell if isinstance(cell, Cell) else Cell(str(cell))
                tag = "th" if i == 0 else "td"
                css = ' class="num"' if c.numeric else ""
                cells.append(f"<{tag}{css}{_attrs(c.data)}>{html.escape(c.text)}</{tag}>")
            out.append("<tr>" + "".join(cells) + "</tr>")
        out.append("</tbody></table></div>")
        self.markup("".join(out))

    def figure(self, ident: str, fig: Any, caption: str | None = None, height_px: int | None = None) -> None:
        """A slot for the Plotly figure ``fig`` (a ``plotly.graph_objects.Figure``), drawn by the page's script."""
        import plotly.io as pio

        self.figures[ident] = json.loads(pio.to_json(fig, validate=False, engine="json"))
        style = f' style="height:{height_px}px"' if height_px else ""
        text = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        self.markup(f'<figure><div class="plot" id="{html.escape(ident)}"{style}></div>{text}</figure>')

    def render(self) -> str:
        """The page as one string."""
        data = {"figures": self.figures, "map": self.map, "config": PLOT_CONFIG}
        payload = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
        return "\n".join(
            [
                "<!DOCTYPE html>",
                '<html lang="en" data-rpbench="loading">',
                "<head>",
                '<meta charset="utf-8">',
                '<meta name="viewport" content="width=device-width, initial-scale=1">',
                f'<meta name="generator" content="rpbench, Plotly {html.escape(assets.plotly_version())}">',
                f"<title>{html.escape(self.title)}</title>",
                f"<style>{assets.text('page.css')}</style>",
                "</head>",
                "<body>",
                "<main>",
                '<p id="rpbench-status" class="status">Drawing the figures (this page needs JavaScript)…</p>',
                *self.blocks,
                "</main>",
                f'<script type="application/gzip+base64" id="rpbench-plotly">{assets.plotly_bundle()}</script>',
                f'<script type="application/json" id="rpbench-data">{payload}</script>',
                f"<script>{assets.text('page.js')}</script>",
                "</body>",
                "</html>",
                "",
            ]
        )


def _class(css: str | None) -> str:
    return f' class="{html.escape(css)}"' if css else ""
