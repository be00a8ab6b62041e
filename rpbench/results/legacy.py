"""KPI names that earlier rpbench versions wrote, mapped to today's where a results table is read.

Every reader of a tidy KPI table (``kpis.csv``, and a parent folder's ``by_day.csv``, ``summary.csv``,
``sweep.csv``, ``units.csv``, ``leaderboard.csv``) passes it through :func:`current_names`, so that
``rpbench report``, ``combine`` and ``check`` read older folders as they read new ones:

* ``competitive_ratio`` (a run's saving / Oracle-1's) is ``saving_over_oracle1``: Oracle-1 bounds
  nothing, so that quotient was never a competitive ratio;
* the ``bound`` run's ``pairing_ratio``, ``avg_detour_m`` and ``avg_shared_m`` describe its matching and
  bound nothing: :data:`~rpbench.results.metrics.BOUND_MATCHING_KPIS` names them apart (in a table that
  holds none of those names: a parent's table of today holds the old names too, as the bound's empty cells
  of rows other runs fill).
"""

from __future__ import annotations

import pandas as pd

from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.ratios import BOUND

#: Old KPI name -> today's, for every run.
LEGACY_KPIS = {"competitive_ratio": "saving_over_oracle1"}


def current_names(tidy: pd.DataFrame) -> pd.DataFrame:
    """``tidy`` (columns ``kpi`` and, where it has one, ``run``) with older KPI names replaced by today's."""
    if "kpi" not in tidy.columns:
        return tidy
    kpi = tidy["kpi"].replace(LEGACY_KPIS)
    if "run" in tidy.columns:
        bound = (tidy["run"].astype(str) == BOUND).to_numpy()
        # a table holding the new names is today's: its bound rows under the old names are empty cells
        if not kpi[bound].isin(list(BOUND_MATCHING_KPIS.values())).any():
            kpi = kpi.where(~bound, kpi.replace(BOUND_MATCHING_KPIS))
    return tidy.assign(kpi=kpi)
