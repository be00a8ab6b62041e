"""rpbench's 2017-05-01 predictions vs the authors' published ones (docs/algorithms.md §2.7, A12).

The authors' file ``predict_result_2017-05-01_0800-0900.csv.gz`` is keyed by
the ``OD_id`` of the per-day OD table; rpbench's per-OD table is joined to it
through ``(origin_id, destination_id)``.  Column meanings follow the authors'
prediction code (TR-B conventions): ``matching_prob`` = P_w; ``ride_distance``,
``detour_distance``, ``shared_distance``, ``saved_distance`` = expectations over
all orders of the OD; ``*_for_taker`` = given the order became a taker;
``*_for_seeker`` = ``p_s`` x (mean given paired as seeker) [+ ``(1-p_s) l_w``
for the ride].  Saved distances are the pair's total saving, not doubled.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data import read_authors_predictions, read_day_od_shares
from rpbench.data.od_rates import AUTHORS_PREDICTION_COLUMNS
from rpbench.predict.prediction import Prediction


def joined(prediction: Prediction, data_dir: Path) -> pd.DataFrame:
    """One row per OD present in both: ``<column>_ours`` and ``<column>_authors``."""
    ours = prediction.per_od_table().drop(columns=["od_id"])
    keys = read_day_od_shares(data_dir)[["od_id", "origin_id", "destination_id"]]
    theirs = read_authors_predictions(data_dir)
    frame = keys.merge(ours, on=["origin_id", "destination_id"], how="inner")
    return frame.merge(theirs, on="od_id", how="inner", suffixes=("_ours", "_authors"))


def compare(prediction: Prediction, data_dir: Path) -> tuple[dict, pd.DataFrame]:
    """Per-column agreement statistics and the joined per-OD frame."""
    # scipy.stats takes 0.3-0.4 s to import; only this comparison needs it, not every rpbench command.
    from scipy import stats

    frame = joined(prediction, data_dir)
    rows = []
    for col in AUTHORS_PREDICTION_COLUMNS:
        ours, theirs = frame[f"{col}_ours"].to_numpy(), frame[f"{col}_authors"].to_numpy()
        ok = np.isfinite(ours) & np.isfinite(theirs)
        ours, theirs = ours[ok], theirs[ok]
        varied = len(ours) > 2 and np.std(ours) > 0 and np.std(theirs) > 0
        rows.append(
            {
                "column": col,
                "n": int(ok.sum()),
                "mean_ours": float(ours.mean()) if len(ours) else None,
                "mean_authors": float(theirs.mean()) if len(theirs) else None,
                "mean_diff": float((ours - theirs).mean()) if len(ours) else None,
                "mean_abs_diff": float(np.abs(ours - theirs).mean()) if len(ours) else None,
                "median_ratio": float(np.median(ours[theirs != 0] / theirs[theirs != 0]))
                if (theirs != 0).any()
                else None,
                "pearson": float(stats.pearsonr(ours, theirs)[0]) if varied else None,
                "spearman": float(stats.spearmanr(ours, theirs)[0]) if varied else None,
            }
        )
    table = pd.DataFrame(rows)
    summary = {
        "ods_joined": len(frame),
        "ods_ours": len(prediction.rates),
        "ods_authors": len(read_authors_predictions(data_dir)),
        "columns": table.to_dict(orient="records"),
    }
    return summary, frame
