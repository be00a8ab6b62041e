"""Readers for OD demand-rate tables and the authors' published predictions.

* ``demand_0800_0900/month_5_OD.csv.gz``: 39,510 OD pairs, ``lambda`` in orders
  per minute averaged over the 21 days 2017-05-01..21, 08:00-09:00
  (sum 51.83/min = 65,304 orders / 1,260 min).
* ``demand_0800_0900/OD_2017-05-01_0800-0900.csv``: 1,698 OD pairs of one day;
  there ``lambda`` is the OD's *share* of that day's orders (sums to 1).
* ``demand_0800_0900/predict_result_2017-05-01_0800-0900.csv.gz``: the
  authors' per-OD predictions for the OD pairs of the per-day table.

Rates are returned in orders per second (rpbench's unit for λ_w).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench.data._table import FLOAT, INT, read_table
from rpbench.exceptions import DataError

MONTH_OD_FILE = Path("demand_0800_0900") / "month_5_OD.csv.gz"
DAY_OD_FILE = Path("demand_0800_0900") / "OD_2017-05-01_0800-0900.csv"
AUTHORS_PREDICTION_FILE = Path("demand_0800_0900") / "predict_result_2017-05-01_0800-0900.csv.gz"

#: Sanity bound on one OD pair's rate (the whole Haikou table sums to 52 orders per minute).
MAX_RATE_PER_MIN = 1e4
_OD_COLUMNS = {"OD_id": INT, "origin_id": INT, "destination_id": INT, "lambda": FLOAT}


def read_od_rates(path: Path) -> pd.DataFrame:
    """An OD table in the ``month_5_OD`` format (``lambda`` per minute).

    Returns ``od_id``, ``origin_id``, ``destination_id``, ``rate_per_s``.
    """
    frame = read_table(path, "OD rate", _OD_COLUMNS, rename={"OD_id": "od_id"})
    if (frame["lambda"] < 0).any():
        row = int((frame["lambda"] < 0).to_numpy().nonzero()[0][0])
        raise DataError(f"OD rate file {str(path)!r}, data row {row + 1}: negative rate {frame['lambda'][row]}")
    if (frame["lambda"] > MAX_RATE_PER_MIN).any():
        # Finite but absurd rates overflow the table's sum to inf, and every drawn probability becomes NaN.
        row = int((frame["lambda"] > MAX_RATE_PER_MIN).to_numpy().nonzero()[0][0])
        raise DataError(
            f"OD rate file {str(path)!r}, data row {row + 1}: rate {frame['lambda'][row]:g} per minute "
            f"exceeds {MAX_RATE_PER_MIN:g}; lambda is in orders per minute"
        )
    frame["rate_per_s"] = frame.pop("lambda") / 60.0
    return frame


def read_month_od_rates(data_dir: Path) -> pd.DataFrame:
    """The 21-day OD rate table (the paper's "May 1-21 demand rates")."""
    return read_od_rates(data_dir / MONTH_OD_FILE)


def read_day_od_shares(data_dir: Path) -> pd.DataFrame:
    """The 2017-05-01 per-day OD table: ``od_id``, ``origin_id``, ``destination_id``, ``share``."""
    path = data_dir / DAY_OD_FILE
    frame = read_table(path, "per-day OD", _OD_COLUMNS, rename={"OD_id": "od_id", "lambda": "share"})
    return frame


#: The columns of the authors' per-OD prediction file: the pairing probability and the expected distances,
#: for any passenger, as a taker and as a seeker.
AUTHORS_PREDICTION_COLUMNS = (
    "matching_prob",
    "ride_distance",
    "detour_distance",
    "shared_distance",
    "saved_distance",
    "ride_distance_for_taker",
    "detour_distance_for_taker",
    "shared_distance_for_taker",
    "saved_distance_for_taker",
    "ride_distance_for_seeker",
    "detour_distance_for_seeker",
    "shared_distance_for_seeker",
    "saved_distance_for_seeker",
)


def read_authors_predictions(data_dir: Path) -> pd.DataFrame:
    """The authors' per-OD predictions for 2017-05-01 (keyed by ``od_id`` of the per-day table)."""
    path = data_dir / AUTHORS_PREDICTION_FILE
    spec = {"OD_id": INT, **{c: FLOAT for c in AUTHORS_PREDICTION_COLUMNS}}
    return read_table(path, "authors' prediction", spec, rename={"OD_id": "od_id"})
