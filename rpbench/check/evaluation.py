"""An evaluation folder's own checks, in the order each needs the one before.

1. ``protocol`` (:mod:`.protocol`): the recorded protocol is whole and hashes to its digest;
2. ``protocol-units`` (:mod:`.units`): the units are the protocol's days x seeds, each run as it says;
3. ``parent-tables`` (:mod:`.tables`): units.csv, leaderboard.csv and paired.csv are recomputed from the
   units' KPI tables under the recorded protocol; ``ranking`` (:mod:`.ranking`) the leaderboard's groups and
   ranks;
4. ``leaderboard-runs`` (:mod:`.coverage`): no run the units hold is left out of what the evaluation shows;
5. ``report`` and ``report-html`` (:mod:`.evaluation_report`): report.md, table.tex and report.html are the
   rendering of the recomputed tables.

The units themselves are checked one by one by the entry point (:mod:`.tree`): in full from their event logs,
or as published light copies (:mod:`.light`).
"""

from __future__ import annotations

from pathlib import Path

from rpbench import results
from rpbench.check.core import RunCheck
from rpbench.check.coverage import check_coverage
from rpbench.check.evaluation_report import check_evaluation_report
from rpbench.check.protocol import read_protocol
from rpbench.check.ranking import check_ranking
from rpbench.check.tables import TABLES_CHECK, compare_table
from rpbench.check.units import check_units
from rpbench.exceptions import RpbenchError, one_line
from rpbench.report.evaluation import board_metrics, evaluation_runs, tables, unit_records
from rpbench.results.layout import LEADERBOARD, PAIRED, UNITS
from rpbench.results.runs import run_styles

#: What the recomputed tables are compared by, and on.
UNIT_KEYS, UNIT_VALUES = ["day", "seed", "run", "kpi"], ["value"]
BOARD_KEYS, BOARD_VALUES = ["run", "kpi"], ["mean", "ci_low", "ci_high", "days", "seeds"]
PAIR_KEYS = ["a", "b", "kpi"]
PAIR_VALUES = ["mean_diff", "ci_low", "ci_high", "wilcoxon_p", "days_a_above", "days_a_below", "days_tied"]


def check_evaluation(fc: RunCheck, parent: Path, meta: dict) -> None:
    """Every check of an evaluation's own files (see the module docstring)."""
    protocol = read_protocol(fc, meta)
    if protocol is None:
        fc.skip(TABLES_CHECK, "without a recorded protocol the tables cannot be recomputed (see [protocol])")
        return
    check_units(fc, parent, meta, protocol)
    try:
        recomputed = tables(parent)
        records = unit_records(parent)
        styles = run_styles(results.read_meta(parent / meta["children"][0]))
    except (RpbenchError, KeyError, ValueError, TypeError, IndexError) as exc:
        fc.skip(
            TABLES_CHECK,
            f"the units' KPI tables cannot be gathered ({type(exc).__name__}: {one_line(exc)}); their own checks "
            "say why",
        )
        return
    units, board, pairs = recomputed
    compare_table(fc, parent / UNITS, units, UNIT_KEYS, UNIT_VALUES)
    compare_table(fc, parent / LEADERBOARD, board, BOARD_KEYS, BOARD_VALUES)
    check_ranking(fc, parent / LEADERBOARD, board)
    compare_table(fc, parent / PAIRED, pairs, PAIR_KEYS, PAIR_VALUES)
    offline = {
        str(r) for unit in records for r, rec in unit.items() if isinstance(rec, dict) and rec.get("kind") == "oracle"
    }
    metrics = list(protocol.metrics)
    check_coverage(fc, parent, units, board_metrics(metrics), metrics, offline, styles)
    check_evaluation_report(fc, parent, meta, recomputed, evaluation_runs(protocol.strategies, records))
