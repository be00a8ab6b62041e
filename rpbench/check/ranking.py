"""``ranking``: an evaluation's leaderboard ranks the online runs first and the clairvoyant ones apart.

leaderboard.csv records every run's ``group`` (online, clairvoyant, offline) and ``rank``
(:mod:`rpbench.results.ranking`).  The check holds the file to itself (no run ranked above a run of an earlier
group: a clairvoyant run among the online ones) and to the ranking recomputed from the units: each run's group
from the units' meta.json and, for a built-in strategy, its class under the recorded options (so a clairvoyant
flag edited to false in meta.json does not move the run among the online ones), its rank from the means.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench import results
from rpbench.check.core import RunCheck
from rpbench.exceptions import ResultsError, one_line
from rpbench.results.ranking import RANKING_COLUMNS, misranked

RANKING_CHECK = "ranking"


def check_ranking(fc: RunCheck, path: Path, expected: pd.DataFrame) -> None:
    """The ranking leaderboard.csv (``path``) records is consistent and equals ``expected``'s (the leaderboard
    recomputed from the units, with its ranking)."""
    if not path.is_file():
        return  # parent-tables says the file is missing
    try:
        found = results.read_csv(path)
    except ResultsError as exc:
        fc.fail(RANKING_CHECK, one_line(exc))
        return
    if not set(RANKING_COLUMNS) <= set(found.columns):
        fc.skip(RANKING_CHECK, f"{path.name} records no ranking (written before rpbench recorded one)")
        return
    for problem in misranked(found):
        fc.fail(RANKING_CHECK, f"{path.name}: {problem}")
    want = expected.drop_duplicates("run").set_index("run")
    have = found.drop_duplicates("run").set_index("run")
    for run in want.index:
        if run not in have.index:
            continue  # parent-tables says which rows are missing
        group, rank = want.loc[run, "group"], int(want.loc[run, "rank"])
        if have.loc[run, "group"] != group:
            fc.fail(
                RANKING_CHECK,
                f"{path.name} puts {run} among the {have.loc[run, 'group']} runs; its units (meta.json, and the "
                f"strategy under its recorded options) make it {group}",
            )
        elif pd.to_numeric(have.loc[run, "rank"], errors="coerce") != rank:
            fc.fail(RANKING_CHECK, f"{path.name} ranks {run} {have.loc[run, 'rank']}; the units' means rank it {rank}")
    fc.checked["ranked_runs"] = len(want)
