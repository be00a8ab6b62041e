"""``haikou-peak``: one day's real 08:00-09:00 orders on the authors' network.

The orders of ``demand_0800_0900/orders/<date>.csv.gz`` (departures inside
[08:00, 09:00)), sampled at ``sample`` without replacement, request time =
departure time.  Fleet: 25 vehicles per 100 sampled orders (the ratio is a
parameter) placed at random sampled order origins (or random nodes).  Each
passenger's patience K_p ~ N(90 s, 10 s) floored at 30 s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data import read_peak_orders
from rpbench.data.orders import parse_date, peak_order_path
from rpbench.data.paper import PAPER_DATE
from rpbench.scenarios.base import Demand, Fleet, Params, Scenario
from rpbench.scenarios.common import (
    Streams,
    check_sample,
    check_seed,
    draw_patience,
    fleet_size,
    haikou_network,
    make_orders,
    place_fleet,
    require_orders,
)

DEFAULT_SAMPLE = 0.3


def build_peak(
    data_dir: Path,
    *,
    date: str = PAPER_DATE,
    sample: float = DEFAULT_SAMPLE,
    seed: int = 0,
    params: Params | None = None,
    fleet_placement: str = "order_origins",
) -> Scenario:
    params = params or Params()
    sample, seed = check_sample(sample, scenario="haikou-peak"), check_seed(seed)
    day = parse_date(date).isoformat()
    network = haikou_network(data_dir)
    frame = read_peak_orders(data_dir, day)
    origin = network.index_of(frame["origin_id"], what=f"origin node id in the {day} orders")
    destination = network.index_of(frame["destination_id"], what=f"destination node id in the {day} orders")
    rng = Streams(seed)
    n_keep = round(sample * len(frame))
    require_orders(n_keep, len(frame), sample, f"the {day} 08:00-09:00 hour of {str(peak_order_path(data_dir, day))!r}")
    keep = np.sort(rng.sample.choice(len(frame), size=n_keep, replace=False)) if sample < 1 else np.arange(len(frame))
    start = pd.Timestamp(day) + pd.Timedelta(hours=8)
    request_s = (frame["departure_time"] - start).dt.total_seconds().to_numpy()[keep]
    orders = make_orders(
        frame["order_id"].to_numpy()[keep],
        request_s,
        origin[keep],
        destination[keep],
        draw_patience(rng.patience, n_keep, params),
    )
    fleet = Fleet(
        initial_node=place_fleet(rng.fleet, fleet_size(n_keep, params), fleet_placement, orders.origin, network.n_nodes)
    )
    pct = f"{sample * 100:g} %"
    return Scenario(
        name="haikou-peak",
        label=f"Haikou {day} 08:00-09:00, real DiDi orders ({pct} sample, seed {seed})",
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=3600.0,
        start_time=start.isoformat(),
        synthetic=False,
        provenance={
            "source": f"demand_0800_0900/orders/{day}.csv.gz",  # in the data folder (no machine path)
            "date": day,
            "sample": sample,
            "rows_in_hour": len(frame),
            "fleet_placement": fleet_placement,
        },
        demand=Demand(table="month", data_dir=str(data_dir)),
    )
