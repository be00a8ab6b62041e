"""``haikou-trace``: the real 2017-07-01 00:00-13:06 trace on the predecessor network.

18,367 real orders replayed by the TR-B 2021 authors, on their 724-vertex
central-Haikou network (a different network from the paper's).  The file
gives request times to the minute; rpbench spreads each order uniformly
within its minute (seeded).  The on-duty fleet follows the trace's hourly
demand at the order-driver ratio.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data import read_trace_orders
from rpbench.exceptions import DataError
from rpbench.scenarios.base import Demand, Params, Scenario
from rpbench.scenarios.common import (
    Streams,
    check_sample,
    check_seed,
    draw_patience,
    hourly_fleet,
    make_orders,
    predecessor_network,
    require_orders,
)

TRACE_DATE = "2017-07-01"


def _check_within_day(frame: pd.DataFrame, start: pd.Timestamp) -> None:
    """Every order must depart on the trace's day: the fleet schedule has one entry per hour from
    ``start``, so a time before it breaks the hourly count and one years later allocates a huge schedule."""
    departure = frame["departure_time"]
    outside = ((departure < start) | (departure >= start + pd.Timedelta(days=1))).to_numpy()
    if outside.any():
        row = int(np.flatnonzero(outside)[0])
        raise DataError(
            f"the {TRACE_DATE} trace: order {int(frame['order_id'].iloc[row])} departs at "
            f"{departure.iloc[row]}, outside {TRACE_DATE}; the trace covers that day only"
        )


def build_trace(
    data_dir: Path,
    *,
    sample: float = 1.0,
    seed: int = 0,
    params: Params | None = None,
    fleet_placement: str = "order_origins",
    date: str | None = None,
) -> Scenario:
    params = params or Params()
    sample, seed = check_sample(sample, scenario="haikou-trace"), check_seed(seed)
    network = predecessor_network(data_dir)
    frame = read_trace_orders(data_dir)
    origin = network.index_of(frame["origin_id"], what="start_ver in the 2017-07-01 trace")
    destination = network.index_of(frame["destination_id"], what="end_ver in the 2017-07-01 trace")
    rng = Streams(seed)
    n_keep = round(sample * len(frame))
    require_orders(n_keep, len(frame), sample, f"the {TRACE_DATE} trace")
    keep = np.sort(rng.sample.choice(len(frame), size=n_keep, replace=False)) if sample < 1 else np.arange(len(frame))
    start = pd.Timestamp(TRACE_DATE)
    _check_within_day(frame, start)
    minute_s = (frame["departure_time"] - start).dt.total_seconds().to_numpy()[keep]
    request_s = minute_s + rng.times.uniform(0.0, 60.0, size=n_keep)
    orders = make_orders(
        frame["order_id"].to_numpy()[keep],
        request_s,
        origin[keep],
        destination[keep],
        draw_patience(rng.patience, n_keep, params),
    )
    hours = int(np.ceil(max(request_s.max() if n_keep else 0.0, 1.0) / 3600.0))
    per_hour = np.bincount((request_s // 3600).astype(int), minlength=hours)
    fleet = hourly_fleet(rng.fleet, per_hour, params, fleet_placement, orders.origin, network.n_nodes)
    return Scenario(
        name="haikou-trace",
        label=(
            f"Haikou {TRACE_DATE} 00:00-13:06 real trace on the TR-B 2021 network "
            f"({sample * 100:g} % sample, seed {seed})"
        ),
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=hours * 3600.0,
        start_time=start.isoformat(),
        synthetic=False,
        provenance={
            "source": "predecessor_trb2021_network",  # in the data folder (no machine path)
            "date": TRACE_DATE,
            "sample": sample,
            "fleet_placement": fleet_placement,
        },
        demand=Demand(data_dir=str(data_dir)),  # its own orders: the month table is on another network
    )
