"""An evaluation's ranking: the online runs, then the clairvoyant ones ranked apart, then the offline runs.

A clairvoyant run read the day's orders before they were revealed, so it competes with no online strategy;
an offline run (the bound, the oracles) is a reference, not a schedule.  Within each :data:`GROUPS` entry,
runs are ranked by the mean of the protocol's first metric, highest first.  ``leaderboard.csv`` records the
ranking on every row, the run's ``group`` and ``rank`` (its place, 1 = first), so that ``rpbench check``
recomputes it (``ranking``) and a clairvoyant run ranked among the online ones is caught.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from rpbench.results.lookahead import reads_future

#: The groups of a ranking, in ranking order.
GROUPS = ("online", "clairvoyant", "offline")
#: The columns of leaderboard.csv that record the ranking.
RANKING_COLUMNS = ("group", "rank")


def run_groups(units: Sequence[Mapping[str, Any]], runs: Sequence[str]) -> dict[str, str]:
    """Each of ``runs``' group from its records in the units' meta.json (``units``: one ``runs`` mapping per
    unit): offline for an offline run, clairvoyant when any unit records that it read the future or its
    built-in strategy's class says so under its options (:func:`~.lookahead.reads_future`), else online."""
    out = {}
    for run in runs:
        records = [u[run] for u in units if isinstance(u.get(run), Mapping)]
        if any(r.get("kind") == "oracle" for r in records):
            out[run] = "offline"
        elif any(reads_future(run, r) for r in records):
            out[run] = "clairvoyant"
        else:
            out[run] = "online"
    return out


def ranking(board: pd.DataFrame, groups: Mapping[str, str], metric: str, runs: Sequence[str]) -> list[str]:
    """``runs`` in ranking order: by group (:data:`GROUPS`), within a group by the mean of ``metric`` in
    ``board`` (leaderboard rows run, kpi, mean), highest first; runs without that mean last, in their order."""
    mean = board[board["kpi"] == metric].set_index("run")["mean"]

    def key(run: str) -> tuple[int, int, float, int]:
        value = float(mean.get(run, np.nan))
        return GROUPS.index(groups.get(run, "online")), int(np.isnan(value)), -np.nan_to_num(value), runs.index(run)

    return sorted(runs, key=key)


def ranked(board: pd.DataFrame, groups: Mapping[str, str], metric: str, runs: Sequence[str]) -> pd.DataFrame:
    """``board`` with the ranking on every row: the run's ``group`` and ``rank``."""
    place = {run: k + 1 for k, run in enumerate(ranking(board, groups, metric, runs))}
    return board.assign(group=board["run"].map(groups), rank=board["run"].map(place))


def misranked(board: pd.DataFrame) -> list[str]:
    """What is wrong with the ranking a leaderboard records (columns run, group, rank): a run given several
    groups or ranks, a group not of :data:`GROUPS`, a missing rank, or a run ranked above a run of an earlier
    group (a clairvoyant run among the online ones)."""
    problems = []
    per_run = board.groupby("run", sort=False)[list(RANKING_COLUMNS)].nunique(dropna=False)
    problems += [f"run {r} has several groups or ranks" for r in per_run.index[(per_run > 1).any(axis=1)]]
    first = board.drop_duplicates("run").set_index("run")
    rank = pd.to_numeric(first["rank"], errors="coerce")
    for run in first.index:
        group = first.loc[run, "group"]
        if group not in GROUPS:
            problems.append(f"run {run} is in group {group!r}, not one of {', '.join(GROUPS)}")
        elif np.isnan(rank[run]):
            problems.append(f"run {run} has no rank")
        else:
            earlier = first["group"].isin(GROUPS[: GROUPS.index(group)]) & (rank > rank[run])
            if earlier.any():
                other = first.index[earlier][0]
                problems.append(
                    f"{group} run {run} is ranked {rank[run]:g}, above the {first.loc[other, 'group']} run {other} "
                    f"(ranked {rank[other]:g})"
                )
    return problems
