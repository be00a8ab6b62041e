"""``report.html``: a results folder as one self-contained, interactive web page with a map.

:func:`write_html` renders it from the folder's files alone (:mod:`.pages`); the page embeds Plotly's
script once and fetches nothing (:mod:`.page`, :mod:`.assets`), draws the report's figures
interactively (:mod:`.figures`) and the road network with each strategy's pooled pairs, solo trips and
cancelled requests over time (:mod:`.mapdata`).
"""

from rpbench.report.html.pages import REPORT_HTML, write_html

__all__ = ["REPORT_HTML", "write_html"]
