"""Readers for the Haikou data folder (one module per source, see its SOURCE.md), and the paper's own
printed values (:mod:`.paper`).

Readers return plain numpy arrays or pandas frames with validated columns;
they never build graphs or scenarios (that is :mod:`rpbench.network` and
:mod:`rpbench.scenarios.base`).
"""

from rpbench.data.hourly_counts import hourly_counts_for, read_hourly_counts
from rpbench.data.od_rates import read_authors_predictions, read_day_od_shares, read_month_od_rates, read_od_rates
from rpbench.data.orders import (
    available_peak_dates,
    parse_date,
    read_gaia_sample,
    read_peak_orders,
    read_raw_peak_orders,
    read_trace_orders,
)
from rpbench.data.road import NetworkTables, read_haikou_network, read_predecessor_network

__all__ = [
    "NetworkTables",
    "available_peak_dates",
    "hourly_counts_for",
    "parse_date",
    "read_authors_predictions",
    "read_day_od_shares",
    "read_gaia_sample",
    "read_haikou_network",
    "read_hourly_counts",
    "read_month_od_rates",
    "read_od_rates",
    "read_peak_orders",
    "read_predecessor_network",
    "read_raw_peak_orders",
    "read_trace_orders",
]
