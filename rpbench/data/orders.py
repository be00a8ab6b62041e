"""Readers for order lists: peak-hour orders, raw coordinates, the GAIA sample, the 2017-07-01 trace.

* ``demand_0800_0900/orders/YYYY-MM-DD.csv.gz``: real orders already snapped to
  network nodes.  Only departures inside [date 08:00, date 09:00) are kept, as
  the authors' simulator does (2,018 of 2,035 rows on 2017-05-01).  Any date
  with a file in that format works; :func:`available_peak_dates` lists them.
  A repeated order id is a ``DataError``; an hour without orders reads as an
  empty frame (the ``haikou-peak`` generator refuses to simulate it).
* ``demand_0800_0900/raw_orders_2017-05-01_0800-0900_by_departure_time.csv.gz``
  and ``samples_and_aggregates/dwv_order_make_haikou_1_min.csv.gz``: raw
  lon/lat orders, to be snapped by :func:`rpbench.network.snap`.  The
  departure-time file is *not* the input of the authors' committed 2017-05-01
  outputs: those come from the 1,766 orders selected by ``arrive_time``
  (``raw_orders_2017-05-01_0800-0900_by_arrive_time.csv.gz``), sampled with
  pandas ``random_state=1`` (530 orders, 132 vehicles); that input is read by
  :mod:`rpbench.data.paper_orders` and built by the ``haikou-paper-input``
  scenario.  The days 2017-05-02.. of the committed outputs use the order
  files above (all rows sampled, then released only inside the hour).
* ``predecessor_trb2021_network/SIMULATION_RESULTS_ALL_DIDI_CHUXING_HAIKOU_2017-07-01.csv.gz``:
  the real 2017-07-01 00:00-13:06 trace on the predecessor network.
"""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import pandas as pd

from rpbench.data._table import DATETIME, FLOAT, INT, read_table
from rpbench.exceptions import DataError, DataNotFoundError, ParameterError
from rpbench.files import file_problem, is_missing

PEAK_DIR = Path("demand_0800_0900") / "orders"
RAW_PEAK_FILE = Path("demand_0800_0900") / "raw_orders_2017-05-01_0800-0900_by_departure_time.csv.gz"
GAIA_SAMPLE_FILE = Path("samples_and_aggregates") / "dwv_order_make_haikou_1_min.csv.gz"
TRACE_FILE = Path("predecessor_trb2021_network") / "SIMULATION_RESULTS_ALL_DIDI_CHUXING_HAIKOU_2017-07-01.csv.gz"

_PREFIX = "dwv_order_make_haikou_1."
_DATE_RE = re.compile(r"^(\d{4}-\d{2}-\d{2})\.csv\.gz$")


def parse_date(text: str) -> dt.date:
    """Parse ``YYYY-MM-DD`` with a clear error."""
    try:
        return dt.date.fromisoformat(str(text))
    except ValueError:
        raise ParameterError(f"date {text!r} is not of the form YYYY-MM-DD") from None


def available_peak_dates(data_dir: Path) -> list[str]:
    """Dates (``YYYY-MM-DD``) that have a peak-hour order file, sorted."""
    folder = data_dir / PEAK_DIR
    if not folder.is_dir():
        return []
    return sorted(m.group(1) for p in folder.iterdir() if (m := _DATE_RE.match(p.name)))


def peak_order_path(data_dir: Path, date: str) -> Path:
    """Path of the peak-hour order file of ``date``, with a clear error when missing."""
    day = parse_date(date).isoformat()
    path = data_dir / PEAK_DIR / f"{day}.csv.gz"
    problem = file_problem(path)
    if problem is not None and not is_missing(problem):
        raise DataError(f"the peak-hour order file of {day}, {str(path)!r}, {problem}")
    if problem is not None:
        have = available_peak_dates(data_dir)
        listed = f"available: {', '.join(have)}" if have else f"no order files in {data_dir / PEAK_DIR}"
        raise DataNotFoundError(f"no peak-hour order file for {day} ({str(path)!r} does not exist); {listed}")
    return path


def read_peak_orders(data_dir: Path, date: str, *, start_hour: int = 8) -> pd.DataFrame:
    """Real orders of ``date`` departing in [start_hour:00, start_hour+1:00).

    Returns columns ``order_id``, ``departure_time`` (datetime), ``origin_id``,
    ``destination_id`` (network node ids), sorted by departure time then id.
    """
    path = peak_order_path(data_dir, date)
    frame = read_table(
        path,
        "peak-hour orders",
        {
            _PREFIX + "order_id": INT,
            _PREFIX + "departure_time": DATETIME,
            "origin_id": INT,
            "destination_id": INT,
        },
        rename={_PREFIX + "order_id": "order_id", _PREFIX + "departure_time": "departure_time"},
    )
    start = pd.Timestamp(parse_date(date)) + pd.Timedelta(hours=start_hour)
    inside = (frame["departure_time"] >= start) & (frame["departure_time"] < start + pd.Timedelta(hours=1))
    frame = frame[inside].sort_values(["departure_time", "order_id"], kind="stable")
    _check_unique_ids(frame["order_id"], path, "peak-hour orders")
    return frame.reset_index(drop=True)


def _check_unique_ids(ids: pd.Series, path: Path, what: str) -> None:
    duplicated = ids.duplicated()
    if duplicated.any():
        raise DataError(f"{what} file {str(path)!r}: order id {int(ids[duplicated].iloc[0])} appears more than once")


def read_raw_peak_orders(data_dir: Path) -> pd.DataFrame:
    """Raw coordinates of the 2017-05-01 08:00-09:00 orders (2,035 rows).

    Columns ``order_id``, ``departure_time``, ``origin_lon``, ``origin_lat``,
    ``dest_lon``, ``dest_lat``.
    """
    path = data_dir / RAW_PEAK_FILE
    names = {
        "order_id": INT,
        "departure_time": DATETIME,
        "starting_lng": FLOAT,
        "starting_lat": FLOAT,
        "dest_lng": FLOAT,
        "dest_lat": FLOAT,
    }
    frame = read_table(
        path, "raw peak-hour orders", {_PREFIX + k: v for k, v in names.items()}, rename={_PREFIX + k: k for k in names}
    )
    return _rename_coordinates(frame)


def read_gaia_sample(data_dir: Path) -> pd.DataFrame:
    """The 13,481-row GAIA sample of raw file 1 (about 1-2 % of each day).

    Same columns as :func:`read_raw_peak_orders`.
    """
    path = data_dir / GAIA_SAMPLE_FILE
    frame = read_table(
        path,
        "GAIA sample orders",
        {
            "order_id": INT,
            "departure_time": DATETIME,
            "starting_lng": FLOAT,
            "starting_lat": FLOAT,
            "dest_lng": FLOAT,
            "dest_lat": FLOAT,
        },
    )
    return _rename_coordinates(frame)


def _rename_coordinates(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.rename(
        columns={
            "starting_lng": "origin_lon",
            "starting_lat": "origin_lat",
            "dest_lng": "dest_lon",
            "dest_lat": "dest_lat",
        }
    )


def read_trace_orders(data_dir: Path) -> pd.DataFrame:
    """The real 2017-07-01 00:00-13:06 trace on the predecessor network (18,367 orders).

    Columns ``order_id``, ``departure_time`` (minute resolution in the file),
    ``origin_id``, ``destination_id`` (predecessor vertex ids).
    """
    path = data_dir / TRACE_FILE
    frame = read_table(
        path,
        "2017-07-01 trace",
        {
            "passenger_id": INT,
            "real_start_time": DATETIME,
            "start_ver": INT,
            "end_ver": INT,
        },
        rename={
            "passenger_id": "order_id",
            "real_start_time": "departure_time",
            "start_ver": "origin_id",
            "end_ver": "destination_id",
        },
    )
    if not frame["order_id"].is_unique:
        raise DataError(f"2017-07-01 trace file {str(path)!r}: passenger_id is not unique")
    return frame.sort_values(["departure_time", "order_id"], kind="stable").reset_index(drop=True)
