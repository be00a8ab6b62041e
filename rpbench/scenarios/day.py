"""``haikou-day``: a 24-hour SYNTHETIC stand-in for a full Haikou day.

No public full-day order list exists (SOURCE.md, "Not found anywhere
reachable"), so this scenario is labelled synthetic wherever it is shown.
It keeps what is real: the chosen date's hourly order volumes
(``data_dayly_hourly_count.csv``; 52,124 orders on 2017-05-01) and the
road network.  OD pairs are drawn in proportion to the 21-day OD rate table
(which is measured over 08:00-09:00: the spatial pattern of the morning
peak is applied to every hour, a stated simplification).  Within each hour
the ``round(sample * count)`` requests are placed uniformly at random, which
is a Poisson process conditioned on the hour's count, so ``sample = 1.0``
reproduces the day's real total exactly.  The on-duty fleet follows the
hourly demand at the order-driver ratio.

``sample = k > 1`` is a demand multiplier, a stress test: the same hourly
rates and OD table, ``round(k * count)`` requests an hour drawn by the same
process (a Poisson process of k times the volume, not copies of the day's
orders), and the fleet following those counts by the same ratio.  It is as
synthetic as the day itself, only larger (no city recorded such a day).  The
draws are the same code as for ``sample <= 1``, so a fraction gives the
orders it always gave.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data import hourly_counts_for, read_month_od_rates
from rpbench.data.orders import parse_date
from rpbench.data.paper import PAPER_DATE
from rpbench.exceptions import DataError
from rpbench.scenarios.base import Demand, Params, Scenario
from rpbench.scenarios.common import (
    MAX_DEMAND_MULTIPLIER,
    Streams,
    check_sample,
    check_seed,
    draw_patience,
    haikou_network,
    hourly_fleet,
    make_orders,
    require_orders,
)


def build_day(
    data_dir: Path,
    *,
    date: str = PAPER_DATE,
    sample: float = 1.0,
    seed: int = 0,
    params: Params | None = None,
    fleet_placement: str = "order_origins",
) -> Scenario:
    params = params or Params()
    sample = check_sample(sample, scenario="haikou-day", most=MAX_DEMAND_MULTIPLIER, real=False)
    seed = check_seed(seed)
    day = parse_date(date).isoformat()
    network = haikou_network(data_dir)
    hourly = hourly_counts_for(data_dir, day)
    rates = read_month_od_rates(data_dir)
    origin_all = network.index_of(rates["origin_id"], what="origin node id in the OD rate table")
    dest_all = network.index_of(rates["destination_id"], what="destination node id in the OD rate table")
    weight = rates["rate_per_s"].to_numpy()
    if weight.sum() <= 0:
        raise DataError("the OD rate table has no positive rate to draw OD pairs from")
    rng = Streams(seed)
    per_hour = np.round(sample * hourly).astype(np.int64)
    n = int(per_hour.sum())
    require_orders(n, int(hourly.sum()), sample, f"{day} in the hourly counts")
    hour = np.repeat(np.arange(24), per_hour)
    request_s = hour * 3600.0 + rng.times.uniform(0.0, 3600.0, size=n)
    od = rng.od.choice(len(weight), size=n, p=weight / weight.sum())
    orders = make_orders(np.arange(n), request_s, origin_all[od], dest_all[od], draw_patience(rng.patience, n, params))
    fleet = hourly_fleet(rng.fleet, per_hour, params, fleet_placement, orders.origin, network.n_nodes)
    start = pd.Timestamp(day)
    return Scenario(
        name="haikou-day",
        label=(
            f"SYNTHETIC full-day stand-in for Haikou {day}: real hourly volumes, OD pairs drawn from the "
            f"21-day 08:00-09:00 OD rates ({_volume(sample, int(hourly.sum()))}, seed {seed})"
        ),
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=24 * 3600.0,
        start_time=start.isoformat(),
        synthetic=True,
        provenance={
            # in the data folder (no machine path)
            "source": "samples_and_aggregates/data_dayly_hourly_count.csv + demand_0800_0900/month_5_OD.csv.gz",
            "date": day,
            "sample": sample,
            "orders_per_hour": per_hour.tolist(),
            "fleet_placement": fleet_placement,
        },
        demand=Demand(table="month", data_dir=str(data_dir), orders_per_hour=tuple(float(n) for n in per_hour)),
    )


def _volume(sample: float, total: int) -> str:
    """The label's volume: a fraction of the day's orders, or a multiplier's k times them."""
    if sample <= 1:
        return f"{sample * 100:g} % of {total} orders"
    return f"DEMAND x{sample:g}: {sample:g} times the {total} orders' volume, a stress test"
