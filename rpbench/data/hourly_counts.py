"""Reader for ``samples_and_aggregates/data_dayly_hourly_count.csv``.

Orders per day and per hour (by departure time) for 2017-05-01..10-31:
``date`` (``MM/DD``, year 2017), ``day_count``, ``hour_count`` (a list of 24).
It is the diurnal profile of the ``haikou-day`` stand-in.
"""

from __future__ import annotations

import ast
import datetime as dt
from pathlib import Path

import numpy as np

from rpbench.data._table import INT, TEXT, read_table
from rpbench.data.orders import parse_date
from rpbench.exceptions import DataError, DataNotFoundError

HOURLY_FILE = Path("samples_and_aggregates") / "data_dayly_hourly_count.csv"
_YEAR = 2017
#: Sanity bound, ~200 times Haikou's busiest hour (about 5,000 orders).
MAX_ORDERS_PER_HOUR = 1_000_000


def read_hourly_counts(data_dir: Path) -> dict[str, np.ndarray]:
    """Map ``YYYY-MM-DD`` -> 24 hourly order counts (int64)."""
    path = data_dir / HOURLY_FILE
    frame = read_table(path, "hourly counts", {"date": TEXT, "day_count": INT, "hour_count": TEXT})
    out: dict[str, np.ndarray] = {}
    for row, (date, total, hours) in enumerate(
        zip(frame["date"], frame["day_count"], frame["hour_count"], strict=True)
    ):
        where = f"hourly counts file {str(path)!r}, data row {row + 1}"
        try:
            month, day = (int(x) for x in str(date).split("/"))
            key = dt.date(_YEAR, month, day).isoformat()
        except ValueError:
            raise DataError(f"{where}: date {date!r} is not MM/DD") from None
        try:
            counts = np.asarray(ast.literal_eval(str(hours)), dtype=np.int64)
        except (ValueError, SyntaxError, TypeError, OverflowError, RecursionError, MemoryError):
            raise DataError(f"{where}: hour_count {hours!r} is not a list of 24 integers") from None
        if counts.shape != (24,) or (counts < 0).any():
            raise DataError(f"{where}: hour_count must hold 24 non-negative integers, got {hours!r}")
        if (counts > MAX_ORDERS_PER_HOUR).any():
            # The day scenario draws that many orders: an absurd count would exhaust memory, not fail.
            raise DataError(
                f"{where}: an hour_count above {MAX_ORDERS_PER_HOUR:,} orders is not plausible "
                f"(got {int(counts.max()):,})"
            )
        if int(counts.sum()) != int(total):
            raise DataError(f"{where}: hour_count sums to {int(counts.sum())}, day_count says {int(total)}")
        out[key] = counts
    return out


def hourly_counts_for(data_dir: Path, date: str) -> np.ndarray:
    """The 24 hourly counts of ``date``, with a clear error when the date is absent."""
    day = parse_date(date).isoformat()
    table = read_hourly_counts(data_dir)
    if day not in table:
        span = f"{min(table)}..{max(table)}" if table else "none"
        raise DataNotFoundError(f"no hourly counts for {day} in {data_dir / HOURLY_FILE} (dates present: {span})")
    return table[day]
