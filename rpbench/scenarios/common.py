"""Pieces shared by the scenario generators: cached networks, seeded draws, fleets."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from rpbench.data import read_haikou_network, read_predecessor_network
from rpbench.exceptions import NoOrdersError, ParameterError
from rpbench.network import RoadNetwork
from rpbench.scenarios.base import Fleet, Orders, Params

FLEET_PLACEMENTS = ("order_origins", "random_nodes")


@lru_cache(maxsize=4)
def haikou_network(data_dir: Path) -> RoadNetwork:
    """The authors' Haikou network (read once per process and data folder)."""
    return RoadNetwork.from_tables(read_haikou_network(data_dir))


@lru_cache(maxsize=4)
def predecessor_network(data_dir: Path) -> RoadNetwork:
    """The TR-B 2021 network of the 2017-07-01 trace."""
    return RoadNetwork.from_tables(read_predecessor_network(data_dir))


class Streams:
    """Independent seeded random streams, one per purpose.

    Changing how one thing is drawn (say, fleet placement) never changes
    another (the sampled orders) for the same seed.
    """

    # New names go last: each stream is the seed's child at its position, so earlier ones keep their draws.
    NAMES = ("sample", "times", "od", "patience", "fleet", "spread", "history")

    def __init__(self, seed: int):
        children = np.random.SeedSequence(int(seed)).spawn(len(self.NAMES))
        self._rng = {name: np.random.default_rng(s) for name, s in zip(self.NAMES, children, strict=True)}

    def __getattr__(self, name: str) -> np.random.Generator:
        try:
            return self._rng[name]
        except KeyError:
            raise AttributeError(name) from None


#: The largest ``--sample`` of a scenario that generates its orders and takes a demand multiplier: k > 1 is
#: k times the volume, drawn anew from the same rates (``haikou-day --sample 4``: about 208,000 orders).
MAX_DEMAND_MULTIPLIER = 100.0


def check_sample(
    sample: float, *, scenario: str | None = None, most: float = 1.0, real: bool = True, multipliers: str = ""
) -> float:
    """``sample`` as a float: a fraction of the orders in (0, 1], or, for a scenario that generates its orders
    and takes a demand multiplier (``most`` > 1), k times the volume up to ``most``.  Beyond the scenario's
    ``most``, one line naming ``scenario`` and why: a sample of ``real`` orders cannot exceed them, a
    generator without a multiplier (``real=False``) draws a fixed volume; ``multipliers`` names the scenarios
    that take one."""
    number = isinstance(sample, (int, float, np.floating))
    if number and 0 < float(sample) <= max(most, 1.0):
        return float(sample)
    named = f" for scenario {scenario!r}" if scenario else ""
    shown = f"{float(sample):g}" if number else repr(sample)
    if not number or not float(sample) > 1:  # not a number, nan, or not positive
        if most > 1:
            raise ParameterError(
                f"--sample {shown} must be > 0{named} (1.0 = the generated volume, k > 1 = k times it)"
            )
        raise ParameterError(f"--sample {shown} must lie in (0, 1] (1.0 = every order)")
    if most > 1:
        raise ParameterError(f"--sample {shown} is out of range (0 < value <= {most:g}){named}")
    why = (
        "its orders are real, and a sample of real orders cannot exceed them (1.0 = every order)"
        if real
        else "its generator draws a fixed volume (1.0 = all of it)"
    )
    also = f"; a demand multiplier k > 1 applies only to the synthetic {multipliers}" if multipliers else ""
    raise ParameterError(f"--sample {shown} is out of range (0 < value <= 1){named}: {why}{also}")


def check_seed(seed: int) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"--seed {seed!r} must be a non-negative integer")
    return int(seed)


def require_orders(n_keep: int, n_total: int, sample: float, where: str) -> None:
    """Refuse a scenario without orders: a run of it would only write an empty results folder."""
    if n_total == 0:
        raise NoOrdersError(f"no orders to simulate: {where} holds no order")
    if n_keep == 0:
        raise NoOrdersError(
            f"no orders to simulate: --sample {sample:g} keeps none of the {n_total} orders of {where}; raise --sample"
        )


def draw_patience(rng: np.random.Generator, n: int, params: Params) -> np.ndarray:
    """K_p ~ N(mean, sd) floored at ``patience_floor_s`` (paper §4.1, SEED-CODE floor)."""
    k = rng.normal(params.patience_mean_s, params.patience_sd_s, size=n)
    return np.maximum(k, params.patience_floor_s)


def make_orders(order_id, request_s, origin, destination, patience_s) -> Orders:
    """Orders sorted by (request time, id)."""
    order = np.lexsort((np.asarray(order_id), np.asarray(request_s)))
    return Orders(
        order_id=np.asarray(order_id, dtype=np.int64)[order],
        request_s=np.asarray(request_s, dtype=np.float64)[order],
        origin=np.asarray(origin, dtype=np.int32)[order],
        destination=np.asarray(destination, dtype=np.int32)[order],
        patience_s=np.asarray(patience_s, dtype=np.float64)[order],
    )


def fleet_size(n_orders: int, params: Params) -> int:
    """Vehicles for ``n_orders`` at the order-driver ratio (at least one)."""
    return max(1, round(n_orders * params.vehicles_per_100_orders / 100.0))


def place_fleet(
    rng: np.random.Generator, n_vehicles: int, placement: str, origins: np.ndarray, n_nodes: int
) -> np.ndarray:
    """Initial vehicle nodes: random order origins (default) or random nodes."""
    if placement == "order_origins" and len(origins):
        return rng.choice(origins, size=n_vehicles, replace=True).astype(np.int32)
    if placement in FLEET_PLACEMENTS:
        return rng.integers(0, n_nodes, size=n_vehicles).astype(np.int32)
    raise ParameterError(f"fleet placement {placement!r} unknown; expected one of {', '.join(FLEET_PLACEMENTS)}")


def hourly_fleet(
    rng: np.random.Generator,
    orders_per_hour: np.ndarray,
    params: Params,
    placement: str,
    origins: np.ndarray,
    n_nodes: int,
) -> Fleet:
    """A fleet whose on-duty count follows hourly demand at the order-driver ratio."""
    counts = np.array([fleet_size(int(n), params) if n > 0 else 0 for n in orders_per_hour], dtype=np.int64)
    n_vehicles = max(1, int(counts.max()))
    return Fleet(
        initial_node=place_fleet(rng, n_vehicles, placement, origins, n_nodes),
        online_times_s=np.arange(len(counts), dtype=np.float64) * 3600.0,
        online_count=counts,
    )
