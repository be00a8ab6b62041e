"""``lattice``: a small synthetic grid city whose every block takes exactly one batch interval to drive.

A ``size x size`` two-way grid with every block ``v·Δt`` long (83.3 m at the paper's 30 km/h and
Δt = 10 s; 250 m with ``--param dt_s=30``).  Vehicles start at nodes at t = 0 and never stand still
(vacant ones cruise or are repositioned), so in every round every vehicle stands exactly at a node and
every pick-up and drop-off falls on a round: the simulator's whole offline decision problem is finite
and discrete, and :mod:`rpbench.oracle.exact` solves it to proven optimality (docs/bound.md, "Exact
optima on lattice cities").

Demand: ``round(sample · 100)`` requests at uniform times over the first :data:`HORIZON_S` seconds,
60 % of origins near three "residential" hot spots and 60 % of destinations near two "business" ones
(as the toy city, :mod:`rpbench.scenarios.toy`); 25 vehicles per 100 orders by default, so the sample
0.3 holds 30 orders and 8 vehicles, 0.8 holds 80 orders and 20 vehicles.  Its demand history (what an
online FL reads instead of the day's orders) is the same generator on :data:`HISTORY_DAYS` past days,
each a full hour at the same rate.
"""

from __future__ import annotations

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.network import RoadNetwork
from rpbench.scenarios.base import Demand, Fleet, History, Params, Scenario
from rpbench.scenarios.common import (
    Streams,
    check_sample,
    check_seed,
    draw_patience,
    fleet_size,
    make_orders,
    place_fleet,
    require_orders,
)
from rpbench.scenarios.toy import HISTORY_DAYS, grid_demand, grid_history, grid_of

#: Nodes per side of the grid.
SIZE = 10
#: Orders at sample 1.0, requested over the first :data:`HORIZON_S` seconds.
LATTICE_BASE_ORDERS = 100
HORIZON_S = 1800.0


def lattice_network(size: int, block_m: float) -> RoadNetwork:
    """A ``size x size`` two-way grid with every arc exactly ``block_m`` long (node ids ``0..size²-1``)."""
    if not isinstance(size, (int, np.integer)) or size < 2:
        raise ParameterError(f"lattice size {size!r} must be an integer >= 2")
    if not np.isfinite(block_m) or block_m <= 0:
        raise ParameterError(f"lattice block length {block_m!r} m must be > 0 (speed x batch interval)")
    return grid_of(size, block_m, np.full(2 * size * (size - 1), float(block_m)), f"lattice-{size}")


def lattice_history(seed: int, n: int, size: int) -> History:
    """Past days of the lattice city of ``seed``: each an hour of its generator at the day's rate (``n`` orders
    per :data:`HORIZON_S`), drawn at seeds that are never a scenario's own."""
    per_hour = round(n * 3600.0 / HORIZON_S)
    seeds = [2**33 + HISTORY_DAYS * int(seed) + k for k in range(HISTORY_DAYS)]
    source = f"the lattice generator on {len(seeds)} past hours (other seeds, {per_hour} orders an hour)"
    return grid_history(seeds, per_hour, size, source)


def build_lattice(
    *,
    sample: float = 0.3,
    seed: int = 0,
    params: Params | None = None,
    size: int = SIZE,
    fleet_placement: str = "order_origins",
    data_dir=None,
    date: str | None = None,
) -> Scenario:
    params = params or Params()
    sample, seed = check_sample(sample, scenario="lattice", real=False), check_seed(seed)
    block_m = params.speed_mps * params.dt_s
    network = lattice_network(size, block_m)
    rng = Streams(seed)
    n = round(sample * LATTICE_BASE_ORDERS)
    require_orders(n, LATTICE_BASE_ORDERS, sample, "the lattice city")
    request_s, origin, destination = grid_demand(rng, n, size, HORIZON_S)
    orders = make_orders(np.arange(n), request_s, origin, destination, draw_patience(rng.patience, n, params))
    fleet = Fleet(
        initial_node=place_fleet(rng.fleet, fleet_size(n, params), fleet_placement, orders.origin, network.n_nodes)
    )
    return Scenario(
        name="lattice",
        label=(
            f"SYNTHETIC lattice city ({size}x{size} grid of {block_m:g} m blocks, one per batch interval; "
            f"{n} orders in {HORIZON_S / 60:g} min, seed {seed})"
        ),
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=HORIZON_S,
        start_time="2017-05-01T08:00:00",
        synthetic=True,
        provenance={
            "source": "generated in code (rpbench.scenarios.lattice)",
            "sample": sample,
            "size": size,
            "block_m": block_m,
            "fleet_placement": fleet_placement,
        },
        demand=Demand(table="history", history=lattice_history(seed, n, size)),
    )
