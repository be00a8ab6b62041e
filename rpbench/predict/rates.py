"""OD demand rates λ_w in orders per second (docs/algorithms.md §2.1).

:class:`OdRates` is the one input format of the prediction model: OD pairs as
internal node indices of a :class:`~rpbench.network.RoadNetwork`, each with
its rate.  It is kept in a canonical order (sorted by origin, then
destination, duplicates merged by summing their rates), so two tables that
list the same ODs in a different order give the same prediction and the
same cache key.

Sources:

* :func:`month_rates` — the 21-day table ``month_5_OD.csv.gz`` (May 1-21,
  08:00-09:00), the paper's choice.
* :func:`table_rates` — any OD table in that format (``lambda`` per minute).
* :func:`peak_order_rates` — one date's peak-hour orders, ``count / 3600 s``.
* :func:`day_table_rates` — the per-day OD table of 2017-05-01 (the OD set of
  the authors' published predictions), ``count / 3600 s``.
* :func:`scenario_rates` / :func:`order_rates` — a scenario's orders,
  ``count / horizon``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.data import read_day_od_shares, read_month_od_rates, read_od_rates, read_peak_orders
from rpbench.data.paper import PAPER_DATE
from rpbench.exceptions import DataError, ParameterError
from rpbench.network import RoadNetwork
from rpbench.units import HOUR_S

#: Named rate sources of :func:`load_rates` (a path to an OD table CSV is accepted too).
RATE_KINDS = ("month", "day", "day-table")


@dataclass(frozen=True, eq=False)
class OdRates:
    """OD pairs (internal node indices) with demand rates in orders per second."""

    origin: np.ndarray  # int32 node index
    destination: np.ndarray  # int32 node index
    rate_per_s: np.ndarray  # float64 λ_w >= 0
    od_id: np.ndarray  # int64 id in the source table (-1 when none)
    source: str = ""

    def __post_init__(self) -> None:
        n = len(self.origin)
        for name in ("destination", "rate_per_s", "od_id"):
            if len(getattr(self, name)) != n:
                raise ParameterError(f"OD rates: column {name} has {len(getattr(self, name))} rows, expected {n}")
        rate = self.rate_per_s
        if n and not np.all(np.isfinite(rate)):
            raise DataError(
                f"OD rates ({self.source}): rate of OD row {int(np.flatnonzero(~np.isfinite(rate))[0])} "
                "is not a finite number"
            )
        if n and np.any(rate < 0):
            row = int(np.flatnonzero(rate < 0)[0])
            raise DataError(
                f"OD rates ({self.source}): negative rate {rate[row]!r} orders/s at OD row {row}; rates must be >= 0"
            )
        if n and np.any(np.diff(self.key(1 << 31)) <= 0):
            raise ParameterError(
                "OD rates must be sorted by (origin, destination) without duplicates; "
                "build them with OdRates.from_arrays"
            )

    def __len__(self) -> int:
        return len(self.origin)

    def key(self, n_nodes: int) -> np.ndarray:
        """``origin * n_nodes + destination`` as int64 (sorted for a canonical table)."""
        return self.origin.astype(np.int64) * int(n_nodes) + self.destination.astype(np.int64)

    @property
    def total_per_s(self) -> float:
        return float(self.rate_per_s.sum())

    @classmethod
    def from_arrays(cls, origin, destination, rate_per_s, od_id=None, *, n_nodes: int, source: str = "") -> OdRates:
        """Canonical rates from unsorted arrays; repeated ODs are merged (rates summed, first id kept)."""
        origin = np.asarray(origin, dtype=np.int64)
        destination = np.asarray(destination, dtype=np.int64)
        rate = np.asarray(rate_per_s, dtype=np.float64)
        od_id = np.full(len(origin), -1, dtype=np.int64) if od_id is None else np.asarray(od_id, dtype=np.int64)
        if not (len(origin) == len(destination) == len(rate) == len(od_id)):
            raise ParameterError("OD rates: origin, destination, rate and id arrays differ in length")
        for name, arr in (("origin", origin), ("destination", destination)):
            if len(arr) and (arr.min() < 0 or arr.max() >= n_nodes):
                raise DataError(f"OD rates ({source}): {name} node index outside the network (0..{n_nodes - 1})")
        if len(rate) and np.any(~np.isfinite(rate) | (rate < 0)):
            row = int(np.flatnonzero(~np.isfinite(rate) | (rate < 0))[0])
            raise DataError(
                f"OD rates ({source}): rate {rate[row]!r} at row {row} is negative or not finite; "
                "rates must be finite and >= 0"
            )
        key = origin * n_nodes + destination
        order = np.argsort(key, kind="stable")
        key = key[order]
        first = np.ones(len(key), dtype=bool)
        first[1:] = key[1:] != key[:-1]
        group = np.cumsum(first) - 1
        merged = np.bincount(group, weights=rate[order], minlength=int(first.sum())) if len(key) else rate
        pick = order[first]
        return cls(
            origin=origin[pick].astype(np.int32),
            destination=destination[pick].astype(np.int32),
            rate_per_s=np.asarray(merged, dtype=np.float64),
            od_id=od_id[pick],
            source=source,
        )

    def scaled(self, factor: float) -> OdRates:
        """The same ODs with every rate multiplied by ``factor`` (>= 0)."""
        if not np.isfinite(factor) or factor < 0:
            raise ParameterError(f"rate scale factor {factor!r} must be finite and >= 0")
        return OdRates(
            self.origin, self.destination, self.rate_per_s * float(factor), self.od_id, f"{self.source} x{factor:g}"
        )

    def frame(self, network: RoadNetwork) -> pd.DataFrame:
        """``od_id, origin_id, destination_id, rate_per_s`` with file node ids."""
        return pd.DataFrame(
            {
                "od_id": self.od_id,
                "origin_id": network.node_id[self.origin],
                "destination_id": network.node_id[self.destination],
                "rate_per_s": self.rate_per_s,
            }
        )


def rates_from_frame(network: RoadNetwork, frame: pd.DataFrame, *, source: str) -> OdRates:
    """Rates from a frame with ``origin_id``, ``destination_id`` (file node ids), ``rate_per_s`` [, ``od_id``]."""
    origin = network.index_of(frame["origin_id"], what=f"origin node id in {source}")
    destination = network.index_of(frame["destination_id"], what=f"destination node id in {source}")
    od_id = frame["od_id"].to_numpy() if "od_id" in frame else None
    return OdRates.from_arrays(
        origin, destination, frame["rate_per_s"].to_numpy(), od_id, n_nodes=network.n_nodes, source=source
    )


def table_rates(network: RoadNetwork, path: Path) -> OdRates:
    """Any OD table in the ``month_5_OD`` format (``OD_id, origin_id, destination_id, lambda`` per minute)."""
    return rates_from_frame(network, read_od_rates(Path(path)), source=str(path))


def month_rates(network: RoadNetwork, data_dir: Path) -> OdRates:
    """The 21-day (2017-05-01..21, 08:00-09:00) rate table: the paper's λ_w."""
    return rates_from_frame(network, read_month_od_rates(data_dir), source="month_5_OD (21-day mean, 08:00-09:00)")


def rate_basis(period_s: float) -> str:
    """How a rate was counted, for a reader: "orders per hour" or "orders per hour, mean of 10 hours"."""
    hours = period_s / HOUR_S
    return "orders per hour" if hours == 1 else f"orders per hour, mean of {hours:g} hours"


def order_rates(network: RoadNetwork, origin, destination, period_s: float, *, source: str) -> OdRates:
    """λ_w = (orders of OD w) / ``period_s`` from arrays of order origins and destinations (node indices)."""
    if not np.isfinite(period_s) or period_s <= 0:
        raise ParameterError(f"rate period {period_s!r} s must be > 0")
    origin = np.asarray(origin)
    return OdRates.from_arrays(
        origin, destination, np.full(len(origin), 1.0 / period_s), n_nodes=network.n_nodes, source=source
    )


def peak_order_rates(network: RoadNetwork, data_dir: Path, date: str) -> OdRates:
    """One date's 08:00-09:00 real orders: λ_w = count / 3600 s (raises when the date has no file)."""
    frame = read_peak_orders(data_dir, date)
    origin = network.index_of(frame["origin_id"], what=f"origin node id in the {date} orders")
    destination = network.index_of(frame["destination_id"], what=f"destination node id in the {date} orders")
    return order_rates(network, origin, destination, HOUR_S, source=f"{date} 08:00-09:00 orders ({rate_basis(HOUR_S)})")


def day_table_rates(network: RoadNetwork, data_dir: Path) -> OdRates:
    """The per-day OD table of 2017-05-01 (1,698 ODs, keyed by its ``OD_id``): λ_w = count / 3600 s.

    The file stores each OD's *share* of the hour's orders.  The order count
    is recovered as ``share / min(share)`` (the rarest OD has one order; the
    file's 1,766 orders give shares that are exact multiples of 1/1766), and
    it is checked to be whole.
    """
    frame = read_day_od_shares(data_dir)
    share = frame["share"].to_numpy(dtype=float)
    if len(share) == 0 or share.min() <= 0:
        raise DataError("per-day OD table: shares must be positive")
    count = share / share.min()
    if np.abs(count - np.rint(count)).max() > 1e-6:
        raise DataError(
            "per-day OD table: shares are not whole multiples of the smallest share; cannot recover order counts"
        )
    frame = frame.assign(rate_per_s=np.rint(count) / HOUR_S)
    return rates_from_frame(network, frame, source=f"OD_2017-05-01_0800-0900 ({rate_basis(HOUR_S)})")


def scenario_rates(scenario) -> OdRates:
    """λ_w = (orders of OD w in the scenario) / its horizon."""
    o = scenario.orders
    return order_rates(
        scenario.network,
        o.origin,
        o.destination,
        scenario.horizon_s,
        source=f"{scenario.name} orders ({rate_basis(scenario.horizon_s)})",
    )


def load_rates(kind: str, network: RoadNetwork, data_dir: Path, date: str | None = None) -> OdRates:
    """Rates by name: ``month`` (21-day table), ``day`` (``date``'s peak orders, default 2017-05-01),
    ``day-table`` (the 2017-05-01 per-day OD table) or the path of an OD table CSV."""
    if date is not None and kind != "day":
        raise ParameterError(f"--date only applies to --rates day (got --rates {kind})")
    if kind == "month":
        return month_rates(network, data_dir)
    if kind == "day":
        return peak_order_rates(network, data_dir, date or PAPER_DATE)
    if kind == "day-table":
        return day_table_rates(network, data_dir)
    path = Path(kind)
    if path.is_file():
        return table_rates(network, path)
    raise ParameterError(
        f"--rates {kind!r}: expected one of {', '.join(RATE_KINDS)} or the path of an OD "
        "table CSV (OD_id, origin_id, destination_id, lambda per minute)"
    )
