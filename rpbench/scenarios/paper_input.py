"""``haikou-paper-input``: exactly the inputs behind the authors' committed outputs.

Where ``haikou-peak`` draws its own seeded sample, this scenario rebuilds the
authors' simulation input step by step (their ``Simulation.__init__`` and
``step``, read to learn the behaviour, re-implemented here):

1. the day's input file in the authors' row order
   (:func:`rpbench.data.paper_orders.read_paper_orders`: the arrive-time
   selection of 1,766 orders for 2017-05-01, the merged order file otherwise);
2. pandas ``DataFrame.sample(frac=0.3, random_state=1)`` on all its rows
   (530 orders on 2017-05-01) -- the sample keeps pandas' order;
3. ``int(n / 4)`` vehicles (132), vehicle ``i`` at
   ``random.seed(i); random.choice(origins)`` where ``origins`` are the
   sample's distinct origins in sample order;
4. patience ``np.random.seed(row index); np.random.normal(90, 10)`` per
   order, not floored (the authors' FL and RTV floor it at 30 s; their
   engine does that, see :mod:`rpbench.replication`);
5. only orders departing in (08:00, 09:00] are ever released (rounds release
   (t - 10 s, t]); the rest stay in the response-rate denominator, which is
   the whole sample (``provenance['response_denominator']``);
6. a round's new passengers are listed in sample order (``sample_rank``), and
   idle vehicles draw their targets from the sample's distinct origins in
   sample order (``idle_origins``), as the authors' loop does.

The scenario's ``orders`` are the released ones, so rpbench's own engine can
run the same input; its response rate must then be rescaled by
``len(orders) / response_denominator`` to compare with the authors'.
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data.orders import parse_date
from rpbench.data.paper import PAPER_DATE
from rpbench.data.paper_orders import PREDICTION_COLUMNS, paper_order_source, read_paper_orders
from rpbench.scenarios.base import Demand, Fleet, Params, Scenario
from rpbench.scenarios.common import check_sample, haikou_network, make_orders, require_orders

#: The authors' ``demand_ratio`` and ``order_driver_ratio`` (100 / 25).
PAPER_SAMPLE = 0.3
ORDERS_PER_VEHICLE = 4
PANDAS_RANDOM_STATE = 1


@dataclass(frozen=True)
class PaperInput:
    """The scenario plus what only the authors' engine reads."""

    scenario: Scenario
    #: Prediction columns aligned with ``scenario.orders`` (NaN where the OD has no prediction).
    predictions: pd.DataFrame
    #: The authors' response-rate denominator: every sampled order, released or not.
    response_denominator: int
    #: Per order of ``scenario.orders``, its position in the pandas sample: the authors list a round's new
    #: passengers in this order (not by request time), which decides who is "first" in their RTV pair edges.
    sample_rank: np.ndarray | None = None
    #: The sample's distinct origins in sample order (network indices), released or not: the list the
    #: authors place the fleet on and draw idle-vehicle targets from (``order_list['O_location'].unique()``).
    idle_origins: np.ndarray | None = None


def sample_like_pandas(frame: pd.DataFrame, frac: float) -> pd.DataFrame:
    """``frame.sample(frac=frac, random_state=1)``, the authors' sampling call, kept as pandas does it."""
    return frame.sample(frac=frac, random_state=PANDAS_RANDOM_STATE)


def authors_fleet(origins_in_sample_order: np.ndarray, n_vehicles: int) -> np.ndarray:
    """Vehicle ``i`` at ``random.seed(i); random.choice(distinct origins)`` (Python's ``random``)."""
    distinct = list(pd.unique(np.asarray(origins_in_sample_order)))
    return np.array([random.Random(i).choice(distinct) for i in range(n_vehicles)], dtype=np.int64)


def authors_patience(row_index: np.ndarray, mean_s: float = 90.0, sd_s: float = 10.0) -> np.ndarray:
    """Per order ``np.random.seed(row index); np.random.normal(mean, sd)`` (legacy global-seed draws)."""
    return np.array([np.random.RandomState(int(i)).normal(mean_s, sd_s) for i in row_index], dtype=np.float64)


def load_paper_input(
    data_dir: Path, *, date: str = PAPER_DATE, sample: float = PAPER_SAMPLE, params: Params | None = None
) -> PaperInput:
    """Build the authors' input of ``date`` (see the module docstring)."""
    params = params or Params()
    sample = check_sample(sample, scenario="haikou-paper-input")
    day = parse_date(date).isoformat()
    network = haikou_network(data_dir)
    frame = read_paper_orders(data_dir, day)
    drawn = sample_like_pandas(frame, float(sample))
    require_orders(len(drawn), len(frame), float(sample), f"the authors' input of {day}")
    n_vehicles = max(1, int(len(drawn) / ORDERS_PER_VEHICLE))
    fleet_ids = authors_fleet(drawn["origin_id"].to_numpy(), n_vehicles)
    start = pd.Timestamp(day) + pd.Timedelta(hours=8)
    request_s = (drawn["departure_time"] - start).dt.total_seconds().to_numpy()
    released = (request_s > 0) & (request_s <= 3600)
    kept = drawn[released]
    patience = authors_patience(kept.index.to_numpy(), params.patience_mean_s, params.patience_sd_s)
    origin = network.index_of(kept["origin_id"], what=f"origin node id in the authors' {day} input")
    destination = network.index_of(kept["destination_id"], what=f"destination node id in the authors' {day} input")
    orders = make_orders(kept["order_id"].to_numpy(), request_s[released], origin, destination, patience)
    fleet = Fleet(initial_node=network.index_of(fleet_ids, what="vehicle start node").astype(np.int32))
    by_id = kept.set_index("order_id")
    predictions = by_id.loc[orders.order_id, list(PREDICTION_COLUMNS)].reset_index(drop=True)
    rank = pd.Series(np.flatnonzero(released), index=kept["order_id"].to_numpy())
    sample_rank = rank.loc[orders.order_id].to_numpy(dtype=np.int64)
    idle_origins = network.index_of(pd.unique(drawn["origin_id"].to_numpy()), what="sampled origin node id")
    source = paper_order_source(data_dir, day)
    scenario = Scenario(
        name="haikou-paper-input",
        label=(
            f"Haikou {day} 08:00-09:00, the authors' exact input ({source.name}, pandas sample "
            f"frac={float(sample):g} random_state=1: {len(drawn)} orders, {len(orders)} released, "
            f"{n_vehicles} vehicles)"
        ),
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=PANDAS_RANDOM_STATE,
        horizon_s=3600.0,
        start_time=start.isoformat(),
        synthetic=False,
        provenance={
            "source": str(source.relative_to(data_dir)) if source.is_relative_to(data_dir) else source.name,
            "date": day,
            "sample": float(sample),
            "rows_in_file": len(frame),
            "sampled": len(drawn),
            "released": len(orders),
            "response_denominator": len(drawn),
            "fleet_placement": "random.seed(i); random.choice(sampled origins)",
            "sampling": "pandas DataFrame.sample(frac, random_state=1)",
            "patience": "np.random.seed(row index); normal(90, 10), not floored",
            "release_window": "(08:00, 09:00]",
        },
        demand=Demand(table="month", data_dir=str(data_dir)),
    )
    return PaperInput(
        scenario=scenario,
        predictions=predictions,
        response_denominator=len(drawn),
        sample_rank=sample_rank,
        idle_origins=idle_origins.astype(np.int64),
    )


def build_paper_input(
    data_dir: Path,
    *,
    date: str = PAPER_DATE,
    sample: float = PAPER_SAMPLE,
    seed: int = 0,
    params: Params | None = None,
    **_ignored,
) -> Scenario:
    """Registry entry: the scenario alone (``seed`` is fixed by the authors' ``random_state=1``)."""
    return load_paper_input(data_dir, date=date, sample=sample, params=params).scenario
