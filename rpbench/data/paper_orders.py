"""The order files behind the authors' committed outputs, in the row order their simulator saw.

The authors' simulator reads one CSV per day and calls
``DataFrame.sample(frac=0.3, random_state=1)`` on it, so *which* orders are
simulated depends on the file's row order, and each passenger's patience is
seeded by its row index.  This module returns those frames:

* 2017-05-01: the 1,766 orders selected by ``arrive_time`` in 08:00-09:00
  (``raw_orders_2017-05-01_0800-0900_by_arrive_time.csv.gz``, snapped nodes in
  its ``O_loction`` / ``D_loction`` columns).  That file is the raw extract; the
  authors merged it with their per-OD predictions before simulating, and an
  old pandas inner merge groups the rows by OD key in order of first
  appearance.  We apply the same grouping (stable), which is the row order the
  committed 2017-05-01 outputs come from (the response-rate denominator 530 =
  round(0.3 x 1,766) confirms the file, and the authors' code run on the
  grouped rows reproduces their output bit for bit).
  The per-OD predictions (FL's inputs) are joined from
  ``OD_2017-05-01_0800-0900.csv`` and ``predict_result_2017-05-01_0800-0900.csv.gz``.
* every other date: ``orders/<date>.csv.gz`` as it is (already merged and
  grouped by OD, predictions included).  The committed MB and RTV response
  rates of 2017-05-02..14 have exactly round(0.3 x rows of that file) as
  their denominator (928, 926, 922, ...).

Rows departing outside the hour are kept: the authors sample first and never
release them, but they stay in the response-rate denominator.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data._table import open_csv
from rpbench.data.orders import parse_date, peak_order_path
from rpbench.exceptions import DataError

ARRIVE_TIME_FILE = Path("demand_0800_0900") / "raw_orders_2017-05-01_0800-0900_by_arrive_time.csv.gz"
OD_FILE = Path("demand_0800_0900") / "OD_2017-05-01_0800-0900.csv"
PREDICTION_FILE = Path("demand_0800_0900") / "predict_result_2017-05-01_0800-0900.csv.gz"
ARRIVE_TIME_DATE = "2017-05-01"

_PREFIX = "dwv_order_make_haikou_1."
#: Prediction columns FL reads (metres; the authors double the two saved distances when loading).
PREDICTION_COLUMNS = (
    "matching_prob",
    "ride_distance",
    "shared_distance",
    "saved_distance_for_seeker",
    "saved_distance_for_taker",
)
ORDER_FILE_COLUMNS = ("order_id", "departure_time", "origin_id", "destination_id") + PREDICTION_COLUMNS


def paper_order_source(data_dir: Path, date: str) -> Path:
    """The file the authors' committed output of ``date`` was simulated from."""
    day = parse_date(date).isoformat()
    if day == ARRIVE_TIME_DATE and os.path.lexists(data_dir / ARRIVE_TIME_FILE):  # a folder there is named
        return data_dir / ARRIVE_TIME_FILE
    return peak_order_path(data_dir, day)


def read_paper_orders(data_dir: Path, date: str) -> pd.DataFrame:
    """The authors' input frame of ``date`` in their row order (index 0..n-1 = their row index).

    Columns :data:`ORDER_FILE_COLUMNS`; ``departure_time`` is a datetime, the prediction
    columns are NaN where no prediction exists for the order's OD pair.
    """
    day = parse_date(date).isoformat()
    path = paper_order_source(data_dir, day)
    try:
        with open_csv(path, "order") as source:
            raw = pd.read_csv(source, compression=None)
    except DataError:
        raise
    except (OSError, ValueError) as exc:
        raise DataError(f"cannot read the order file {str(path)!r}: {exc}") from None
    if path.name == ARRIVE_TIME_FILE.name:
        frame = _arrive_time_frame(data_dir, raw, path)
    else:
        frame = _merged_frame(raw, path)
    frame["departure_time"] = pd.to_datetime(frame["departure_time"], errors="coerce")
    if frame["departure_time"].isna().any():
        raise DataError(f"order file {str(path)!r}: a departure_time is not a date-time")
    return frame.reset_index(drop=True)


def _require(raw: pd.DataFrame, columns: list[str], path: Path) -> None:
    missing = [c for c in columns if c not in raw.columns]
    if missing:
        raise DataError(f"order file {str(path)!r} lacks column(s) {', '.join(missing)}")


def _merged_frame(raw: pd.DataFrame, path: Path) -> pd.DataFrame:
    need = [_PREFIX + "order_id", _PREFIX + "departure_time", "O_location", "D_location"]
    _require(raw, need, path)
    frame = pd.DataFrame(
        {
            "order_id": raw[need[0]].astype(np.int64),
            "departure_time": raw[need[1]],
            "origin_id": raw["O_location"].astype(np.int64),
            "destination_id": raw["D_location"].astype(np.int64),
        }
    )
    for col in PREDICTION_COLUMNS:
        frame[col] = raw[col].astype(float) if col in raw.columns else np.nan
    return frame


def _arrive_time_frame(data_dir: Path, raw: pd.DataFrame, path: Path) -> pd.DataFrame:
    need = [_PREFIX + "order_id", _PREFIX + "departure_time", "O_loction", "D_loction"]
    _require(raw, need, path)
    frame = pd.DataFrame(
        {
            "order_id": raw[need[0]].astype(np.int64),
            "departure_time": raw[need[1]],
            "origin_id": raw["O_loction"].astype(np.int64),
            "destination_id": raw["D_loction"].astype(np.int64),
        }
    )
    frame = group_by_first_appearance(frame, ["origin_id", "destination_id"])
    return frame.join(_od_predictions(data_dir), on=["origin_id", "destination_id"])


def group_by_first_appearance(frame: pd.DataFrame, key: list[str]) -> pd.DataFrame:
    """Rows grouped by ``key``, groups in order of first appearance, rows stable within a group.

    This is the row order an old pandas inner merge gave its left frame.
    """
    codes = frame.groupby(key, sort=False).ngroup()
    order = np.argsort(codes.to_numpy(), kind="stable")
    return frame.iloc[order].reset_index(drop=True)


def _od_predictions(data_dir: Path) -> pd.DataFrame:
    """Per-OD predictions of 2017-05-01 indexed by (origin_id, destination_id); NaN columns when absent."""
    od_path, pred_path = data_dir / OD_FILE, data_dir / PREDICTION_FILE
    if not (os.path.lexists(od_path) and os.path.lexists(pred_path)):  # optional; open_csv names a wrong kind
        return pd.DataFrame(
            columns=list(PREDICTION_COLUMNS),
            index=pd.MultiIndex.from_arrays([[], []], names=["origin_id", "destination_id"]),
        )
    with open_csv(od_path, "OD") as od_source, open_csv(pred_path, "prediction") as pred_source:
        od = pd.read_csv(od_source, compression=None)
        pred = pd.read_csv(pred_source, compression=None)
    _require(od, ["OD_id", "origin_id", "destination_id"], od_path)
    _require(pred, ["OD_id", *PREDICTION_COLUMNS], pred_path)
    table = od.merge(pred, on="OD_id")
    table["origin_id"] = table["origin_id"].astype(np.int64)
    table["destination_id"] = table["destination_id"].astype(np.int64)
    table = table.drop_duplicates(["origin_id", "destination_id"])
    return table.set_index(["origin_id", "destination_id"])[list(PREDICTION_COLUMNS)]
