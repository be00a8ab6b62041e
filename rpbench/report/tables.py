"""The comparison table for papers: LaTeX (booktabs) and CSV, beside report.md (``table.tex``, ``table.csv``).

Both are the Table 2 layout of :func:`rpbench.report.comparison.markdown_table`: KPIs as rows, runs as
columns.  The LaTeX cells are the report's printed numbers (``\\usepackage{booktabs}``; a column whose
run is not proven optimal carries the report's mark); the CSV carries the raw values, for a paper's own
formatting.
"""

from __future__ import annotations

import pandas as pd

from rpbench.results.metrics import KPI_LABELS
from rpbench.results.runs import Styles, run_label

_LATEX_SPECIAL = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    # the default (OT1) font encoding typesets these as other glyphs
    "<": r"\textless{}",
    ">": r"\textgreater{}",
    "|": r"\textbar{}",
}


def latex_escape(text: str) -> str:
    """``text`` (a label a user or plug-in chose, a caption) as LaTeX text: specials escaped, line breaks (which
    would end a table row or a paragraph) made spaces."""
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in " ".join(str(text).split()))


def latex_table(
    table: pd.DataFrame,
    rows: list[str],
    fmt,
    *,
    caption: str,
    unproven: dict[str, str] | None = None,
    mark: str = "*",
    styles: Styles | None = None,
    note: str | None = None,
) -> str:
    """A booktabs ``table`` environment of ``rows`` (KPI keys) x ``table``'s runs, cells as ``fmt(kpi, value)``
    prints them, captioned; the columns of ``unproven`` runs carry ``mark``; ``note``: a line under the table."""
    runs = [str(c) for c in table.columns]
    unproven = unproven or {}
    head = ["Metric"] + [latex_escape(run_label(r, styles)) + (f"$^{{{mark}}}$" if r in unproven else "") for r in runs]
    body = [[latex_escape(KPI_LABELS.get(k, k))] + [latex_escape(fmt(k, table.loc[k, r])) for r in runs] for k in rows]
    return booktabs(head, body, caption=caption, what="the comparison table", note=note)


def booktabs(head: list[str], body: list[list[str]], *, caption: str, what: str, note: str | None = None) -> str:
    """A booktabs ``table`` environment: ``head`` and ``body`` cells already LaTeX (escaped), the first column
    left-aligned, the others right-aligned; ``what`` names the table in its leading comment; ``note`` (text,
    escaped here) is set in small type under the table."""
    lines = [
        f"% rpbench: {what} (needs \\usepackage{{booktabs}})",
        "\\begin{table}[ht]",
        "\\centering",
        f"\\caption{{{latex_escape(caption)}}}",
        "\\begin{tabular}{l" + "r" * (len(head) - 1) + "}",
        "\\toprule",
        " & ".join(head) + " \\\\",
        "\\midrule",
    ]
    lines += [" & ".join(row) + " \\\\" for row in body]
    lines += ["\\bottomrule", "\\end{tabular}"]
    if note:
        lines += ["", f"\\smallskip{{\\footnotesize {latex_escape(note)}\\par}}"]
    lines += ["\\end{table}", ""]
    return "\n".join(lines)


def csv_table(table: pd.DataFrame, rows: list[str], styles: Styles | None = None) -> pd.DataFrame:
    """The comparison table with raw values: a row per KPI (its key and label), a column per run (its name)."""
    out = table.loc[rows].copy()
    out.insert(0, "metric", [KPI_LABELS.get(k, k) for k in rows])
    out.index.name = "kpi"
    return out
