"""One prediction per scenario hour: the demand rates a scenario implies, τ_0, caching and warm starts.

:func:`scenario_predictions` is what the FL strategies call.  It takes the
rates λ_w from the scenario's :class:`~rpbench.scenarios.base.Demand` (or the
scenario's own orders), rounds τ_0 to :data:`TAU0_RESOLUTION_S` so runs with
nearly equal calibrations share one cached prediction, reuses a solved
prediction from the disk cache, and otherwise solves the fixed point on the
cached structure (:mod:`.list_cache`): the matching sets depend only on the OD
set, the geometry and the priority rule (0.67 GB for the 39,510-OD month
table, built once per machine), while the demand level and τ_0 enter the
fixed point only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.predict.config import PredictConfig
from rpbench.predict.prediction import Prediction, cached_prediction, predict
from rpbench.predict.rates import OdRates, month_rates, order_rates
from rpbench.scenarios.base import Scenario

#: Where λ_w comes from: the scenario's implied demand, the 21-day table, or the scenario's own orders.
RATE_SOURCES = ("auto", "month", "scenario")
#: τ_0 is rounded to this resolution, so runs whose calibrations differ by a few
#: seconds (peak hours of different days, sweep points) share one prediction.
TAU0_RESOLUTION_S = 10.0


def scenario_predictions(
    scenario: Scenario, source: str, tau0_s: np.ndarray, config: PredictConfig
) -> list[Prediction]:
    """One prediction per hour of ``scenario`` (``len(tau0_s)`` hours; hours with equal inputs share one).

    The dispatcher reads per-OD values only, so the hours come back slim
    (24 hours of per-state arrays would be 2.4 GB for the month table); an
    hour that must be solved is warm-started from the previous hour's ρ,
    read back from the cache when that hour was cached.
    """
    hours = len(tau0_s)
    tau0_s = np.maximum(TAU0_RESOLUTION_S, np.round(np.asarray(tau0_s) / TAU0_RESOLUTION_S) * TAU0_RESOLUTION_S)
    rates = hourly_rates(scenario, source, hours)
    net, params = scenario.network, scenario.params
    out: list[Prediction] = []
    memo: dict[tuple, Prediction] = {}
    previous: tuple[OdRates, PredictConfig, Prediction] | None = None
    for h in range(hours):
        cfg = config.replace(tau0_s=float(tau0_s[h]))
        key = (id(rates[h]), cfg.tau0_s)
        if key not in memo:
            prediction = cached_prediction(net, rates[h], params, cfg, slim=True)
            if prediction is None:
                # Warm-start from the previous hour when the OD set is the same (only the demand level moved).
                rho0 = None
                if previous is not None and _same_ods(previous[0], rates[h]):
                    rho0 = (
                        previous[2].rho if len(previous[2].rho) else predict(net, previous[0], params, previous[1]).rho
                    )
                prediction = predict(net, rates[h], params, cfg, rho0=rho0)
            previous = (rates[h], cfg, prediction)
            memo[key] = prediction.slim()
        out.append(memo[key])
    return out


def _same_ods(a: OdRates, b: OdRates) -> bool:
    return len(a) == len(b) and np.array_equal(a.origin, b.origin) and np.array_equal(a.destination, b.destination)


def hourly_rates(scenario: Scenario, source: str, hours: int) -> list[OdRates]:
    """λ_w for each of the first ``hours`` hours of ``scenario`` (objects shared where equal)."""
    if source not in RATE_SOURCES:
        raise ParameterError(f"rates {source!r} unknown; expected one of {', '.join(RATE_SOURCES)}")
    net, demand = scenario.network, scenario.demand
    if source == "auto":
        source = "month" if demand.table == "month" else "scenario"
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
    o = scenario.orders
    hour_of = np.minimum((o.request_s // 3600.0).astype(int), hours - 1)
    return [
        order_rates(
            net,
            o.origin[hour_of == h],
            o.destination[hour_of == h],
            3600.0,
            source=f"{scenario.name} orders of hour {h} (count/3600 s)",
        )
        for h in range(hours)
    ]
