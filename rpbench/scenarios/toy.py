"""``toy``: a small synthetic city generated in code (no data needed).

A ``size x size`` two-way grid with block lengths of 500 m stretched by a
seeded factor in [1, 1.2) (so road distance is never shorter than the
straight line), placed near Haikou's coordinates for plotting.  One hour of
demand: ``round(sample * 400)`` requests at uniform times; 60 % of origins
come from three "residential" hot spots and 60 % of destinations go to two
"business" hot spots, so there is something to pool.  It is rpbench's
built-in default when no data folder exists and the fixture of fast tests.

Its demand history (:class:`~rpbench.scenarios.base.History`, what FL's
prediction reads instead of the day's own orders) is the same generator on
:data:`HISTORY_DAYS` past days: the orders it draws at the seeds
:func:`history_seeds` derives from the scenario's, at the same sample and
grid.  An empirical table like the paper's 21-day one, so an OD never seen
predicts 0 (§2.1); the generator's exact OD probabilities were the
alternative, but they give every one of the 20,592 OD pairs of the 12x12 grid
a rate, and a prediction structure that takes ten times longer to build than
the 3,000 or so pairs of ten days.
"""

from __future__ import annotations

import numpy as np

from rpbench.data.road import NetworkTables
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

BLOCK_M = 500.0
TOY_BASE_ORDERS = 400
_LON0, _LAT0 = 110.30, 19.98
_M_PER_DEG_LAT = 110_540.0
#: Past days in a toy city's demand history.
HISTORY_DAYS = 10


def grid_network(size: int = 12, seed: int = 0) -> RoadNetwork:
    """A seeded ``size x size`` two-way grid (node ids ``0..size²-1``), blocks of 500 m stretched by [1, 1.2)."""
    if not isinstance(size, (int, np.integer)) or size < 2:
        raise ParameterError(f"toy grid size {size!r} must be an integer >= 2")
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 7]))
    n_links = 2 * size * (size - 1)
    return grid_of(size, BLOCK_M, BLOCK_M * (1.0 + 0.2 * rng.random(n_links)), f"toy-grid-{size}")


def grid_of(size: int, spacing_m: float, link_m: np.ndarray, name: str) -> RoadNetwork:
    """A ``size x size`` two-way grid placed near Haikou with nodes ``spacing_m`` apart: the links (every
    right neighbour, then every lower one) ``link_m`` long in both directions."""
    ids = np.arange(size * size)
    row, col = np.divmod(ids, size)
    right = ids[col < size - 1]
    down = ids[row < size - 1]
    a = np.concatenate([right, down])
    b = np.concatenate([right + 1, down + size])
    m_per_deg_lon = _M_PER_DEG_LAT * np.cos(np.radians(_LAT0))
    tables = NetworkTables(
        name=name,
        node_id=ids,
        lon=_LON0 + col * spacing_m / m_per_deg_lon,
        lat=_LAT0 + row * spacing_m / _M_PER_DEG_LAT,
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.concatenate([link_m, link_m]),
        arc_link_id=np.concatenate([np.arange(len(a))] * 2),
        source="generated in code",
    )
    return RoadNetwork.from_tables(tables)


def hotspot_nodes(rng: np.random.Generator, centres: np.ndarray, share: float, n: int, size: int) -> np.ndarray:
    """Nodes near a random hot spot (with probability ``share``) or uniform."""
    uniform = rng.integers(0, size * size, size=n)
    centre = centres[rng.integers(0, len(centres), size=n)]
    r, c = np.divmod(centre, size)
    r = np.clip(r + np.rint(rng.normal(0, 1.2, size=n)).astype(int), 0, size - 1)
    c = np.clip(c + np.rint(rng.normal(0, 1.2, size=n)).astype(int), 0, size - 1)
    return np.where(rng.random(n) < share, r * size + c, uniform)


def history_seeds(seed: int) -> list[int]:
    """The seeds of a toy city's past days: ``2**32 + 10 seed + k`` for k < :data:`HISTORY_DAYS`, never
    ``seed`` itself and never another scenario seed's past day."""
    return [2**32 + HISTORY_DAYS * int(seed) + k for k in range(HISTORY_DAYS)]


def grid_demand(rng: Streams, n: int, size: int, span_s: float = 3600.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` requests at uniform times over ``[0, span_s)`` on a ``size x size`` grid: times (sorted), origins
    near three "residential" hot spots and destinations near two "business" ones (60 % each; node indices)."""
    homes = np.array([1 * size + 1, (size - 2) * size + 2, (size // 2) * size + size - 2])
    work = np.array([(size // 2) * size + size // 2, 2 * size + size - 3])
    origin = hotspot_nodes(rng.od, homes, 0.6, n, size)
    destination = hotspot_nodes(rng.od, work, 0.6, n, size)
    same = origin == destination
    destination[same] = (destination[same] + size + 1) % (size * size)
    return np.sort(rng.times.uniform(0, span_s, size=n)), origin, destination


def grid_history(seeds: list[int], n: int, size: int, source: str) -> History:
    """Past days of the grid generator: ``n`` requests over an hour at each of ``seeds`` (``source``: one line)."""
    days = [grid_demand(Streams(s), n, size) for s in seeds]
    return History(
        request_s=np.concatenate([d[0] for d in days]),
        origin=np.concatenate([d[1] for d in days]).astype(np.int32),
        destination=np.concatenate([d[2] for d in days]).astype(np.int32),
        days=len(days),
        source=source,
    )


def toy_history(seed: int, n: int, size: int) -> History:
    """The demand history of the toy city of ``seed``: its generator's ``n`` requests on each past day."""
    seeds = history_seeds(seed)
    return grid_history(seeds, n, size, f"the toy generator on {len(seeds)} past days (other seeds, {n} orders a day)")


def build_toy(
    *,
    sample: float = 1.0,
    seed: int = 0,
    params: Params | None = None,
    size: int = 12,
    fleet_placement: str = "order_origins",
    data_dir=None,
    date: str | None = None,
) -> Scenario:
    params = params or Params()
    sample, seed = check_sample(sample, scenario="toy", real=False), check_seed(seed)
    network = grid_network(size, seed=0)  # the city stays the same across seeds; demand varies
    rng = Streams(seed)
    n = round(sample * TOY_BASE_ORDERS)
    require_orders(n, TOY_BASE_ORDERS, sample, "the toy city")
    request_s, origin, destination = grid_demand(rng, n, size)
    orders = make_orders(np.arange(n), request_s, origin, destination, draw_patience(rng.patience, n, params))
    fleet = Fleet(
        initial_node=place_fleet(rng.fleet, fleet_size(n, params), fleet_placement, orders.origin, network.n_nodes)
    )
    return Scenario(
        name="toy",
        label=f"SYNTHETIC toy city ({size}x{size} grid, {n} orders in one hour, seed {seed})",
        network=network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=3600.0,
        start_time="2017-05-01T08:00:00",
        synthetic=True,
        provenance={
            "source": "generated in code (rpbench.scenarios.toy)",
            "sample": sample,
            "size": size,
            "fleet_placement": fleet_placement,
        },
        demand=Demand(table="history", history=toy_history(seed, n, size)),
    )
