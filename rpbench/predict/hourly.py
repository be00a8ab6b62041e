"""One prediction per scenario hour: the demand rates a scenario implies, τ_0, caching and the hours in parallel.

:func:`scenario_predictions` is what the FL strategies call.  It takes the
rates λ_w from the scenario's :class:`~rpbench.scenarios.base.Demand` (the
21-day table, or past days of a generator; the scenario's own orders only when
asked for, which reads the future: :func:`reads_realised_orders`), rounds τ_0 to :data:`TAU0_RESOLUTION_S` so runs with
nearly equal calibrations share one cached prediction, reuses a solved
prediction from the disk cache, and otherwise solves the fixed point on the
cached structure (:mod:`.list_cache`): the matching sets depend only on the OD
set, the geometry and the priority rule (0.67 GB for the 39,510-OD month
table, built once per machine and shared by every hour, τ_0 and run), while the
demand level and τ_0 enter the fixed point only.  The hours still to solve are
solved side by side in worker processes (:mod:`.pool`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.predict.config import PredictConfig
from rpbench.predict.pool import solve_predictions
from rpbench.predict.prediction import Prediction, cached_prediction
from rpbench.predict.rates import OdRates, month_rates, order_rates, rate_basis
from rpbench.predict.zones import zone_representatives
from rpbench.scenarios.base import LOOKAHEAD_HINT, Demand, OnlineView, Scenario
from rpbench.units import HOUR_S

#: Where λ_w comes from: the demand known before the day (the 21-day table or the demand history), the 21-day
#: table, the demand history, or the scenario's own orders (the realisation: reading them is clairvoyant).
RATE_SOURCES = ("auto", "month", "history", "scenario")
#: The hours solved one after another, warm-starting each other, in one process: the day's 24 hours make four
#: chains (up to four processes), whose first hours start from ρ = 0 (about 3 sweeps more than a warm start).
CHAIN_HOURS = 6
#: τ_0 is rounded to this resolution, so runs whose calibrations differ by a few
#: seconds (peak hours of different days, sweep points) share one prediction.
TAU0_RESOLUTION_S = 10.0


def scenario_predictions(
    scenario: Scenario | OnlineView,
    source: str,
    tau0_s: np.ndarray,
    config: PredictConfig,
    zone_m: float | None = None,
    *,
    workers: int | None = None,
) -> list[Prediction]:
    """One prediction per hour of ``scenario`` (``len(tau0_s)`` hours; hours with equal inputs share one).

    The dispatcher reads per-OD values only, so the hours come back slim and the hours solved here are
    cached lean (24 hours of per-state arrays would be 2.3 GB for the month table).  The hours to solve are
    cut into chains of :data:`CHAIN_HOURS` consecutive hours of the day, fixed by the hour and not by the
    machine; a chain's hours are solved in turn, each warm-started from the previous one solved (same OD set),
    and the chains side by side in ``workers`` processes (default: the cores; 1: here, one after another;
    :mod:`.pool`), with the same values either way.  ``zone_m``: pool a demand history over zones of this side
    (:func:`history_zone_m`).
    """
    hours = len(tau0_s)
    tau0_s = np.maximum(TAU0_RESOLUTION_S, np.round(np.asarray(tau0_s) / TAU0_RESOLUTION_S) * TAU0_RESOLUTION_S)
    rates = hourly_rates(scenario, source, hours, zone_m)
    net, params = scenario.network, scenario.params
    configs = [config.replace(tau0_s=float(t)) for t in tau0_s]
    keys = [(id(rates[h]), configs[h].tau0_s) for h in range(hours)]
    found: dict[tuple, Prediction] = {}
    missing: dict[tuple, int] = {}  # the first hour of each distinct input not in the cache
    for h, key in enumerate(keys):
        if key in found or key in missing:
            continue
        hit = cached_prediction(net, rates[h], params, configs[h], slim=True)
        if hit is None:
            missing[key] = h
        else:
            found[key] = hit
    chains: dict[int, list[tuple[OdRates, PredictConfig]]] = {}
    for h in missing.values():
        chains.setdefault(h // CHAIN_HOURS, []).append((rates[h], configs[h]))
    solved = solve_predictions(net, params, list(chains.values()), workers)
    found.update(zip(missing, solved, strict=True))
    return [found[key] for key in keys]


def rate_source(source: str, demand: Demand) -> str:
    """What rates ``source`` reads for a scenario of ``demand``: ``auto`` is its table (``month`` or
    ``history``) and, when it has none, its own orders (``scenario``)."""
    if source not in RATE_SOURCES:
        raise ParameterError(f"rates {source!r} unknown; expected one of {', '.join(RATE_SOURCES)}")
    if source != "auto":
        return source
    return demand.table if demand.table in ("month", "history") else "scenario"


def reads_realised_orders(source: str, demand: Demand) -> bool:
    """Whether rates ``source`` count the scenario's realised orders: a run predicting from them is clairvoyant."""
    return rate_source(source, demand) == "scenario"


def history_zone_m(source: str, demand: Demand, zone_m: float | None = None) -> float | None:
    """The side of the zones a rate ``source`` pools its demand history over: ``zone_m`` when given, else the
    history's own (:attr:`~rpbench.scenarios.base.History.zone_m`); None: not pooled (or not a history)."""
    if rate_source(source, demand) != "history" or demand.history is None:
        return None
    return zone_m if zone_m is not None else demand.history.zone_m


def hourly_rates(
    scenario: Scenario | OnlineView, source: str, hours: int, zone_m: float | None = None
) -> list[OdRates]:
    """λ_w for each of the first ``hours`` hours of ``scenario`` (objects shared where equal); a demand history
    pooled over zones of ``zone_m`` (:func:`history_zone_m`)."""
    net, demand = scenario.network, scenario.demand
    source = rate_source(source, demand)
    if source == "month":
        if demand.data_dir is None or net.name != "haikou":
            raise ParameterError(
                f"FL rates 'month' need the Haikou network and data folder; scenario "
                f"{scenario.name!r} has neither (use --opt fl.rates=scenario)"
            )
        base = month_rates(net, Path(demand.data_dir))
        if demand.orders_per_hour is None:
            return [base] * hours
        # hour h carries n_h orders of the table's OD mix: λ_w(h) = n_h · λ_w / Σλ / 3600
        return [base.scaled(float(n / (base.total_per_s * 3600.0))) for n in demand.orders_per_hour[:hours]]
    if source == "history":
        history = demand.history
        if history is None:
            raise ParameterError(
                f"FL rates 'history': scenario {scenario.name!r} has no demand history "
                "(use --opt fl.rates=month or fl.rates=scenario)"
            )
        # the mean over its days: λ_w(h) = (orders of OD w in hour h of the past days) / (days · 3600 s)
        period_s = history.days * HOUR_S
        origin, destination, what = history.origin, history.destination, history.source
        zone = history_zone_m(source, demand, zone_m)
        if zone is not None:  # per pair of zones, each zone at its representative node
            rep = zone_representatives(net, zone)
            origin, destination, what = rep[origin], rep[destination], f"{what}, pooled over {zone:g} m zones"
            moving = origin != destination  # a trip inside one zone pairs nothing at the zones' scale
            return _per_hour(net, history.request_s[moving], origin[moving], destination[moving], hours, period_s, what)
        return _per_hour(net, history.request_s, origin, destination, hours, period_s, what)
    if isinstance(scenario, OnlineView):  # a strategy that did not say it reads the future
        raise LookaheadError(
            f"{scenario.reader}: FL rates 'scenario' count the scenario's own orders; {LOOKAHEAD_HINT}"
        )
    o = scenario.orders
    return _per_hour(net, o.request_s, o.origin, o.destination, hours, HOUR_S, f"{scenario.name} orders")


def _per_hour(net, request_s, origin, destination, hours: int, period_s: float, what: str) -> list[OdRates]:
    """Rates of each hour's orders (count / ``period_s``; an order after the last hour counts in it)."""
    hour_of = np.minimum((np.asarray(request_s) // HOUR_S).astype(int), hours - 1)
    return [
        order_rates(
            net,
            origin[hour_of == h],
            destination[hour_of == h],
            period_s,
            source=f"{what}, hour {h:02d}:00 ({rate_basis(period_s)})",
        )
        for h in range(hours)
    ]
