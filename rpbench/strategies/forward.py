"""FL and FL-no_delay: the paper's forward-looking strategies (§3.4, Eqs. 15-17).

Both rank the same feasible options as MB (:mod:`.candidates`) with the
predicted expected savings of the seeker/taker model (:mod:`rpbench.predict`):

* **FL** (Eq. 15-16): ``ē(p)²/(ē(p)+pk)·α^k_p`` for a vacant vehicle,
  ``e²/(e+pk)·α^k_p`` for a partially occupied one, ``ē(0,p) - l̄`` for keeping
  the passenger waiting (Eq. 10: ``ē(0,p) = [1-(1-r_w)^{K̄/Δt-k_p}]·[p_s ē(s) +
  (1-p_s) ē(p)]``).  ``0/0 := 0``.
* **FL-no_delay** (Eq. 17): ``ē(p) - pk`` and ``e - pk``, no waiting option
  (waiting gets ``-10⁶ m``, A13).

Partially occupied options with ``e <= 0`` are dropped for both (A11).
``k_p`` is the round number of the passenger (A10), the same in ``α^k_p``
and in ē(0,p).  An OD missing from the rate table predicts 0 (§2.1).

Options (``--opt fl.NAME=VALUE``):

* ``rates``: where λ_w comes from — ``auto`` (default: the 21-day May 1-21
  table for Haikou peak hours, as the paper; for the synthetic full day the
  same table scaled to each hour's volume, which is exactly how that day's
  demand is generated; for other scenarios the scenario's own orders per
  hour), ``month``, ``scenario``.
* ``tau0_s``: sojourn τ_0 of the origin taker state (A4) and
  ``mean_pickup_m``: l̄ of the waiting utility.  Both default to the mean
  pick-up time / distance of an MB calibration run on the same scenario
  (per hour where the scenario spans hours), which the harness computes;
  without it the fallbacks are 120 s and 900 m.  τ_0 is rounded to 10 s so
  that runs with nearly equal calibrations share one cached prediction.
* ``priority``, ``include_origin_state``, ``rho_mode``, ``accel``:
  prediction options (:class:`rpbench.predict.PredictConfig`); FL solves the
  fixed point with Anderson mixing by default (the same fixed point as the
  spec's damped iteration, in about half the sweeps).  Hours of the full-day
  stand-in share one built model and warm-start from the previous hour.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ParameterError
from ..model import Structure
from ..predict import PredictConfig, Prediction, build_model, month_rates, order_rates, solve_model
from ..predict import cache as prediction_cache
from ..scenario import Scenario
from .base import RoundModel, RoundState, Strategy
from .candidates import NO_WAIT_UTILITY_M, JoinOptions, assignment_round, join_options, vacant_options

FALLBACK_TAU0_S = 120.0
FALLBACK_MEAN_PICKUP_M = 900.0
RATE_SOURCES = ("auto", "month", "scenario")
_PREDICT_OPTIONS = ("priority", "include_origin_state", "rho_mode", "accel")


def fraction(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` with ``0/0 := 0`` (§2.8)."""
    out = np.zeros(np.broadcast(num, den).shape)
    np.divide(num, den, out=out, where=den != 0)
    return out


class _ForwardBase(Strategy):
    structure = Structure.ASSIGNMENT

    def __init__(self, **options: Any):
        super().__init__(**options)
        unknown = set(options) - {"rates", "tau0_s", "mean_pickup_m", "order_rule", *_PREDICT_OPTIONS}
        if unknown:
            raise ParameterError(f"{self.name}: unknown option(s) {', '.join(sorted(unknown))}; known: rates, "
                                 f"tau0_s, mean_pickup_m, order_rule, {', '.join(_PREDICT_OPTIONS)}")
        self.rates_source = options.get("rates", "auto")
        if self.rates_source not in RATE_SOURCES:
            raise ParameterError(f"{self.name}: rates {self.rates_source!r} unknown; expected one of "
                                 f"{', '.join(RATE_SOURCES)}")
        self.order_rule = options.get("order_rule", "min_feasible")
        self.predictions: list[Prediction] = []
        self.mean_pickup_m: np.ndarray = np.array([FALLBACK_MEAN_PICKUP_M])

    # ----------------------------------------------------------- predictions
    def prepare(self, scenario: Scenario) -> None:
        hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
        tau0 = _per_hour(self.options.get("tau0_s"), hours, FALLBACK_TAU0_S, "tau0_s")
        self.mean_pickup_m = _per_hour(self.options.get("mean_pickup_m"), hours, FALLBACK_MEAN_PICKUP_M,
                                       "mean_pickup_m")
        # Anderson mixing reaches the same fixed point as the plain damped map in about half the sweeps.
        config = PredictConfig(**{"accel": "anderson",
                                  **{k: self.options[k] for k in _PREDICT_OPTIONS if k in self.options}})
        self.predictions = hourly_predictions(scenario, self.rates_source, tau0, config)

    def prediction_at(self, t_s: float) -> tuple[Prediction, int]:
        hour = min(int(t_s // 3600.0), len(self.predictions) - 1)
        return self.predictions[hour], hour

    def _options(self, state: RoundState):
        vac = vacant_options(state)
        join = join_options(state, self.order_rule)
        good = join.saving_m > 0                                   # A11
        join = JoinOptions(join.p[good], join.v[good], join.pickup_m[good], join.saving_m[good], join.fofo[good])
        prediction, hour = self.prediction_at(state.t_s)
        e_vac = prediction.lookup(state.p_origin, state.p_destination).e_vacant
        return vac, join, prediction, hour, e_vac


class ForwardLooking(_ForwardBase):
    name = "fl"
    description = "forward-looking dispatch with intended delay, paper Eqs. (15)-(16)"

    def build(self, state: RoundState) -> RoundModel:
        vac, join, prediction, hour, e_vac = self._options(state)
        alpha_k = state.params.alpha ** state.p_rounds_waited.astype(np.float64)
        ev = e_vac[vac.p]
        u_vac = fraction(ev * ev, ev + vac.pickup_m) * alpha_k[vac.p]
        e = join.saving_m
        u_join = fraction(e * e, e + join.pickup_m) * alpha_k[join.p]
        e_wait = prediction.e_wait(state.p_origin, state.p_destination, state.p_rounds_waited, state.params)
        u_wait = e_wait - self.mean_pickup_m[min(hour, len(self.mean_pickup_m) - 1)]
        return assignment_round(state, vac, u_vac, join, u_join, u_wait, name=self.name)


class ForwardLookingNoDelay(_ForwardBase):
    name = "fl-nd"
    description = "forward-looking dispatch without intended delay, paper Eq. (17)"

    def build(self, state: RoundState) -> RoundModel:
        vac, join, _, _, e_vac = self._options(state)
        return assignment_round(state, vac, e_vac[vac.p] - vac.pickup_m, join, join.saving_m - join.pickup_m,
                                np.full(state.n_passengers, NO_WAIT_UTILITY_M), name=self.name)


def _per_hour(value, hours: int, fallback: float, name: str) -> np.ndarray:
    """A scalar or per-hour list option as an array of ``hours`` values (NaN -> fallback)."""
    if value is None:
        return np.full(hours, fallback)
    arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
    if arr.size == 1:
        arr = np.full(hours, float(arr[0]))
    if len(arr) < hours:
        raise ParameterError(f"option {name} gives {len(arr)} hourly values for {hours} hours")
    arr = np.where(np.isfinite(arr), arr, fallback)[:hours]
    if (arr < 0).any():
        raise ParameterError(f"option {name} must be >= 0")
    return arr


# ---------------------------------------------------------------------- rates
#: τ_0 is rounded to this resolution, so runs whose calibrations differ by a few
#: seconds (peak hours of different days, sweep points) share one prediction.
TAU0_RESOLUTION_S = 10.0
#: The last built prediction model of this process: its matching sets depend only on the OD set,
#: the geometry and the priority rule, and take minutes and gigabytes for the 39,510-OD table.
_BUILT: dict[tuple, Any] = {}


def hourly_predictions(scenario: Scenario, source: str, tau0_s: np.ndarray,
                       config: PredictConfig) -> list[Prediction]:
    """One prediction per scenario hour (shared objects where hours have the same inputs)."""
    hours = len(tau0_s)
    tau0_s = np.maximum(TAU0_RESOLUTION_S, np.round(tau0_s / TAU0_RESOLUTION_S) * TAU0_RESOLUTION_S)
    net, params = scenario.network, scenario.params
    data_dir = scenario.provenance.get("data_dir")
    if source == "auto":
        source = "month" if scenario.name in ("haikou-peak", "haikou-day") else "scenario"
    if source == "month":
        if data_dir is None or net.name != "haikou":
            raise ParameterError(f"FL rates 'month' need the Haikou network and data folder; scenario "
                                 f"{scenario.name!r} has neither (use --opt fl.rates=scenario)")
        base = month_rates(net, Path(data_dir))
        if scenario.name == "haikou-day":
            # The stand-in draws hour h's orders from this table: λ_w(h) = n_h · λ_w / Σλ / 3600.
            per_hour = np.asarray(scenario.provenance["orders_per_hour"], dtype=float)
            rates = [base.scaled(float(n / (base.total_per_s * 3600.0))) for n in per_hour[:hours]]
        else:
            rates = [base] * hours
    else:   # the scenario's own orders, hour by hour
        o = scenario.orders
        hour_of = np.minimum((o.request_s // 3600.0).astype(int), hours - 1)
        rates = [order_rates(net, o.origin[hour_of == h], o.destination[hour_of == h], 3600.0,
                             source=f"{scenario.name} orders of hour {h} (count/3600 s)") for h in range(hours)]
    out: list[Prediction] = []
    memo: dict[tuple, Prediction] = {}
    previous: Prediction | None = None
    for h in range(hours):
        cfg = config.replace(tau0_s=float(tau0_s[h]))
        key = (id(rates[h]), cfg.tau0_s)
        if key not in memo:
            # Warm-start from the previous hour when the OD set is the same (only the demand level moved).
            same_ods = previous is not None and len(previous.rates) == len(rates[h]) and \
                np.array_equal(previous.rates.origin, rates[h].origin) and \
                np.array_equal(previous.rates.destination, rates[h].destination)
            warm = previous.rho if same_ods else None
            memo[key] = solve_cached(net, rates[h], params, cfg, rho0=warm)
            previous = memo[key]
        out.append(memo[key])
    return out


def solve_cached(net, rates, params, config: PredictConfig, *, rho0: np.ndarray | None = None) -> Prediction:
    """:func:`rpbench.predict.predict` with the built model kept in memory across demand levels and τ_0."""
    key = prediction_cache.cache_key(net, rates, params, config)
    hit = prediction_cache.load(key, net, rates, config)
    if hit is not None:
        return hit
    structure = (net.content_hash, len(rates), hash(rates.key(net.n_nodes).tobytes()),
                 tuple(getattr(params, f) for f in prediction_cache.PARAM_FIELDS),
                 config.include_origin_state, config.priority, config.keep_nonpositive, config.order_rule)
    model = _BUILT.get(structure)
    if model is None:
        _BUILT.clear()                      # keep one model: the month table's takes gigabytes
        print(f"rpbench: building the seeker/taker prediction model for {len(rates):,} OD pairs "
              f"({rates.source}); cached afterwards", file=sys.stderr)
        model = build_model(net, rates, params, config)
        _BUILT[structure] = model
    # The demand level and τ_0 enter the fixed point only (the origin states' sojourn).
    space = dataclasses.replace(model.space, tau_s=np.where(model.space.k == 0, config.tau0_s, model.space.tau_s))
    prediction = solve_model(dataclasses.replace(model, rates=rates, config=config, space=space), rho0=rho0)
    prediction_cache.save(key, prediction)
    return prediction
