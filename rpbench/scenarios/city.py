"""``city``: a window of an imported city's day of real trips (``--city NAME --window 08:00-09:00``).

The trips requested inside the window, sampled at ``sample`` without replacement, request time = the
table's time; times the table records to the minute (``time_resolution_s`` 60) are spread uniformly
inside their minute, seeded, so that a minute's requests do not all arrive in one batch round.  Fleet:
the order-driver ratio (25 vehicles per 100 sampled orders) for a window of an hour or less, and one that
follows the hourly demand for a longer window (as the full synthetic Haikou day).  Patience K_p ~ N(90 s,
10 s) floored at 30 s.  The city's default speed (``city.json``) replaces the paper's 30 km/h unless
``--param speed_mps`` is given.

The demand a dispatcher knows before each hour is the city's trips of the hour before it on the same day
(the same sample fraction, seeded), as the scenario's :class:`~rpbench.scenarios.base.History`: FL's
online rates (``rates=auto``), never the hour's own trips.  A city has one day, so there is no month of
history to average; the first hour of the day has none.
"""

from __future__ import annotations

import re

import numpy as np

from rpbench.cities.folder import City
from rpbench.exceptions import ParameterError
from rpbench.scenarios.base import Demand, Fleet, History, Params, Scenario
from rpbench.scenarios.common import (
    Streams,
    check_sample,
    check_seed,
    draw_patience,
    fleet_size,
    hourly_fleet,
    make_orders,
    place_fleet,
    require_orders,
)
from rpbench.units import DAY_S, HOUR_S

#: One hour of a city's trips is sparse per pair of nodes: its rates are pooled over zones of this side
#: (:mod:`rpbench.predict.zones`), chosen on validation hours of Manhattan, never on a tested one (docs/cities.md).
HISTORY_ZONE_M = 2000.0
_WINDOW = re.compile(r"^(\d{1,2}):(\d{2})-(\d{1,2}):(\d{2})$")


def parse_window(text: str) -> tuple[float, float]:
    """``HH:MM-HH:MM`` (end up to 24:00) as seconds from midnight."""
    match = _WINDOW.match(text.strip())
    if match is None:
        raise ParameterError(f"--window {text!r}: a time window HH:MM-HH:MM, e.g. 08:00-09:00 or 00:00-24:00")
    h1, m1, h2, m2 = (int(g) for g in match.groups())
    start, end = h1 * HOUR_S + m1 * 60.0, h2 * HOUR_S + m2 * 60.0
    if m1 > 59 or m2 > 59 or start >= DAY_S or end > DAY_S or end <= start:
        raise ParameterError(f"--window {text!r}: start before end, both within 00:00-24:00")
    return start, end


def window_text(start_s: float, end_s: float) -> str:
    """Seconds from midnight back as ``HH:MM-HH:MM``."""
    return f"{_clock(start_s)}-{_clock(end_s)}"


def _clock(seconds: float) -> str:
    return f"{int(seconds // HOUR_S):02d}:{int(seconds % HOUR_S // 60):02d}"


def build_city(
    city: City,
    *,
    name: str = "city",
    window: str = "08:00-09:00",
    sample: float = 1.0,
    seed: int = 0,
    params: Params | None = None,
    fleet_placement: str = "order_origins",
    source: str | None = None,
    data_dir: str | None = None,
) -> Scenario:
    """The trips of ``city`` in ``window`` as a scenario named ``name`` (``city``, or a built-in city's own);
    ``source``: the ``--city`` it was named by (None: a built-in city's scenario), ``data_dir``: the data
    folder it was made from (both recorded, so that the scenario's other windows can be built, as VF's
    training does)."""
    params = params or Params()
    sample, seed = check_sample(sample, scenario=name), check_seed(seed)
    start_s, end_s = parse_window(window)
    horizon_s = end_s - start_s
    rng = Streams(seed)
    inside = np.flatnonzero((city.request_s >= start_s) & (city.request_s < end_s))
    n_keep = round(sample * len(inside))
    require_orders(n_keep, len(inside), sample, f"the {window_text(start_s, end_s)} window of city {city.name!r}")
    keep = np.sort(rng.sample.choice(inside, size=n_keep, replace=False)) if sample < 1 else inside
    request_s = _spread(city.request_s[keep], city.time_resolution_s, rng.spread) - start_s
    request_s = np.minimum(request_s, np.nextafter(horizon_s, 0.0))
    orders = make_orders(
        keep, request_s, city.origin[keep], city.destination[keep], draw_patience(rng.patience, n_keep, params)
    )
    if horizon_s <= HOUR_S:
        fleet = Fleet(
            initial_node=place_fleet(
                rng.fleet, fleet_size(n_keep, params), fleet_placement, orders.origin, city.network.n_nodes
            )
        )
    else:
        per_hour = np.bincount((orders.request_s // HOUR_S).astype(int), minlength=int(np.ceil(horizon_s / HOUR_S)))
        fleet = hourly_fleet(rng.fleet, per_hour, params, fleet_placement, orders.origin, city.network.n_nodes)
    span = window_text(start_s, end_s)
    day = f" {city.date}" if city.date else ""
    return Scenario(
        name=name,
        label=f"{city.label}{day} {span}, real trips ({sample * 100:g} % sample, seed {seed})",
        network=city.network,
        orders=orders,
        fleet=fleet,
        params=params,
        seed=seed,
        horizon_s=horizon_s,
        start_time=f"{city.date}T{span[:5]}:00" if city.date else f"{span[:5]}:00",  # a day of unknown date: the clock
        synthetic=False,
        provenance={
            "city": city.name,
            **({"city_source": source} if source is not None else {}),
            "city_digest": city.digest,
            "window": span,
            "date": city.date,
            "sample": sample,
            "trips_in_window": len(inside),
            "time_resolution_s": city.time_resolution_s,
            "fleet_placement": fleet_placement,
        },
        demand=Demand(
            table="history", data_dir=data_dir, history=_hour_before(city, start_s, end_s, sample, rng.history)
        ),
    )


def _spread(seconds: np.ndarray, resolution_s: float, rng: np.random.Generator) -> np.ndarray:
    """Times recorded to ``resolution_s`` spread uniformly inside it (times of a 1 s clock as they are)."""
    if resolution_s <= 1.0:
        return seconds
    return seconds + rng.uniform(0.0, resolution_s, size=len(seconds))


def _hour_before(city: City, start_s: float, end_s: float, sample: float, rng: np.random.Generator) -> History:
    """The trips of the hour before each hour of the window, moved one hour on (hour h holds hour h-1's), at
    the scenario's sample fraction: what the platform saw before each hour."""
    seen = np.flatnonzero((city.request_s >= start_s - HOUR_S) & (city.request_s < end_s - HOUR_S))
    seen = np.sort(rng.choice(seen, size=round(sample * len(seen)), replace=False)) if sample < 1 else seen
    return History(
        request_s=city.request_s[seen] + HOUR_S - start_s,
        origin=city.origin[seen].astype(np.int32),
        destination=city.destination[seen].astype(np.int32),
        days=1,
        source=f"{city.name} trips of the hour before each hour, same day",
        zone_m=HISTORY_ZONE_M,
    )
