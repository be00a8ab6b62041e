"""The ``report-html`` check: the comparison table of report.html shows kpis.csv (which the runs' ``kpi``
checks verify), both its printed numbers and the raw values its cells carry for scripts."""

from __future__ import annotations

import html
import math
import re

from rpbench.check.core import RunCheck
from rpbench.check.folder import Folder
from rpbench.check.kpis import older_cells
from rpbench.exceptions import RpbenchError, one_line
from rpbench.report.comparison import fmt, table_rows
from rpbench.results.layout import KPIS, META, REPORT_HTML
from rpbench.results.legacy import LEGACY_KPIS
from rpbench.results.read import load_kpis

_CELL = re.compile(r'<td class="num" data-run="([^"]*)" data-kpi="([^"]*)" data-value="([^"]*)">([^<]*)</td>')
#: Raw values are written with repr(): they round-trip exactly; the ratio rows are recomputed, hence a tolerance.
PAGE_REL_TOL = 1e-12


def check_page(fc: RunCheck, f: Folder) -> None:
    path = f.path / REPORT_HTML
    if not path.is_file():
        fc.skip("report-html", f"the folder has no {REPORT_HTML}")
        return
    try:
        expected = load_kpis(f.path)
    except (RpbenchError, KeyError, ValueError, TypeError, IndexError) as exc:
        fc.skip("report-html", f"{KPIS} or {META} cannot be read ({type(exc).__name__}: {one_line(exc)})")
        return
    text = path.read_text(encoding="utf-8", errors="replace")
    table = text.split('id="comparison-table"', 1)
    if len(table) != 2:
        fc.fail("report-html", f"{REPORT_HTML} has no comparison table")
        return
    cells = _CELL.findall(table[1].split("</table>", 1)[0])
    older, shown_older = older_cells(expected), []
    seen = set()
    for run, kpi, raw, shown in cells:
        run, kpi, shown = html.unescape(run), html.unescape(kpi), html.unescape(shown)
        kpi = LEGACY_KPIS.get(kpi, kpi)  # a page an older rpbench wrote
        seen.add((run, kpi))
        if kpi not in expected.index or run not in expected.columns:
            fc.fail("report-html", f"{REPORT_HTML} shows {kpi} of run {run!r}, which {KPIS} does not hold")
            continue
        value = expected.loc[kpi, run]
        if (kpi, run) in older and shown == fmt(kpi, older[(kpi, run)]):
            shown_older.append(f"{kpi} of {run}")  # what an older rpbench showed where today's shows "/"
            continue
        missing = value is None or (isinstance(value, float) and math.isnan(value))
        try:
            agrees = (
                (raw == "") if missing else math.isclose(float(raw), float(value), rel_tol=PAGE_REL_TOL, abs_tol=1e-12)
            )
        except ValueError:
            agrees = False
        if not agrees or shown != fmt(kpi, value):
            fc.fail(
                "report-html",
                f"{REPORT_HTML} shows {kpi} of {run}: {shown} ({raw or 'no value'}); {KPIS} renders {fmt(kpi, value)}",
            )
    rendered = {(str(r), str(k)) for k in table_rows(expected) for r in expected.columns}
    absent = {(r, k) for r, k in rendered if (r, k) not in seen and not _undefined(expected.loc[k, r])}
    if shown_older:
        fc.skip("report-html", f"{REPORT_HTML} shows cells as an older rpbench did: {', '.join(shown_older)}")
    newer = sorted({k for _, k in absent} - {k for _, k in seen})  # whole rows an older rpbench did not render
    if newer and cells:
        fc.skip("report-html", f"{REPORT_HTML} has no row {', '.join(newer)} (written by an older rpbench)")
        absent = {(r, k) for r, k in absent if k not in newer}
    if not cells or absent:
        fc.fail("report-html", f"{REPORT_HTML}'s comparison table lacks {len(absent) or 'all its'} cells of {KPIS}")
    fc.checked["page_cells"] = len(cells)


def _undefined(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))
