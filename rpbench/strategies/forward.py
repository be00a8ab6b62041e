"""FL and FL-no_delay: the paper's forward-looking strategies (§3.4, Eqs. 13-15).

Both rank the same feasible options as MB (:mod:`.candidates`) with the
predicted expected savings of the seeker/taker model (:mod:`rpbench.predict`):

* **FL** (Eqs. 13-14): ``ē(p)²/(ē(p)+pk)·α^k_p`` for a vacant vehicle,
  ``e²/(e+pk)·α^k_p`` for a partially occupied one, ``ē(0,p) - l̄`` for keeping
  the passenger waiting (Eq. 10: ``ē(0,p) = [1-(1-r_w)^{K̄/Δt-k_p}]·[p_s ē(s) +
  (1-p_s) ē(p)]``).  ``0/0 := 0``.
* **FL-no_delay** (Eq. 15): ``ē(p) - pk`` and ``e - pk``, no waiting option
  (waiting gets ``-10⁶ m``, A13).

Partially occupied options with ``e <= 0`` are dropped for both (A11).
``k_p`` is the round number of the passenger (A10), the same in ``α^k_p``
and in ē(0,p).  An OD missing from the rate table predicts 0 (§2.1).

Options (``--opt fl.NAME=VALUE``):

* ``rates``: where λ_w comes from — ``auto`` (default: the demand known
  before the day, :class:`~rpbench.scenarios.base.Demand`: the 21-day
  May 1-21 table for Haikou peak hours, as the paper; for the synthetic full
  day the same table scaled to each hour's volume, which is exactly how that
  day's demand is generated; for the toy city its generator's past days), ``month``,
  ``history`` (the past days), ``scenario``: the scenario's own orders per hour.
  Counting the day's own orders reads the future, so a run that does (``scenario``,
  or ``auto`` on a scenario without history: the 2017-07-01 trace) is clairvoyant
  (:attr:`~rpbench.strategies.base.Strategy.clairvoyant`) and marked so.
* ``tau0_s``: sojourn τ_0 of the origin taker state (A4) and
  ``mean_pickup_m``: l̄ of the waiting utility.  Both default to the mean
  pick-up time / distance of an MB calibration run on the same scenario
  (per hour where the scenario spans hours), which the harness computes;
  without it the fallbacks are 120 s and 900 m.  τ_0 is rounded to 10 s by
  :func:`rpbench.predict.scenario_predictions` so that runs with nearly equal
  calibrations share one cached prediction.
* ``priority``, ``include_origin_state``, ``rho_mode``, ``accel``:
  prediction options (:class:`rpbench.predict.PredictConfig`); FL solves the
  fixed point with Anderson mixing by default (the same fixed point as the
  spec's damped iteration, in about half the sweeps).  Hours of the full-day
  stand-in share one cached structure; chains of six hours, each hour
  warm-started from the previous one, are solved side by side in ``workers``
  processes (default: the cores), and the predictions do not depend on
  ``workers``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.options import Range, option
from rpbench.predict import RATE_SOURCES, PredictConfig, Prediction, scenario_predictions
from rpbench.predict.config import ACCELERATIONS, PRIORITIES, RHO_MODES
from rpbench.predict.hourly import history_zone_m, reads_realised_orders
from rpbench.predict.zones import zone_representatives
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import (
    NO_WAIT_UTILITY_M,
    JoinOptions,
    VacantOptions,
    assignment_round,
    join_options,
    vacant_options,
)
from rpbench.strategies.myopic import PoolingOptions

if TYPE_CHECKING:
    import pandas as pd

FALLBACK_TAU0_S = 120.0
FALLBACK_MEAN_PICKUP_M = 900.0


@dataclass(frozen=True)
class CalibratedOptions(PoolingOptions):
    """The options :class:`MBCalibrated` completes from an MB run: τ_0 (A4) and l̄ of the waiting utility."""

    # a day bounds a sojourn and R̄'s own bound (1000 km) a mean pick-up distance
    tau0_s: float | tuple[float, ...] | None = option(
        None,
        "τ_0 in seconds, one value or one per hour (default: MB calibration run's mean pick-up time, A4)",
        range=Range(0.0, 86400.0, "s"),
    )
    mean_pickup_m: float | tuple[float, ...] | None = option(
        None,
        "l̄ of the waiting utility in metres, one value or one per hour (default: MB calibration run's)",
        range=Range(0.0, 1e6, "m"),
    )


@dataclass(frozen=True)
class ForwardOptions(CalibratedOptions):
    """FL's and FL-no_delay's options (the prediction's among them, :class:`rpbench.predict.PredictConfig`)."""

    rates: str = option(
        "auto",
        "where λ_w comes from: the demand known before the day, the 21-day table, the demand history, or the "
        "scenario's own orders (clairvoyant)",
        choices=RATE_SOURCES,
    )
    priority: str | None = option(None, "taker priority of the prediction (§2.4, A7)", choices=PRIORITIES)
    include_origin_state: bool | None = option(None, "taker state k = 0 at the origin (A4)")
    rho_mode: str | None = option(None, "how ρ is formed (A8)", choices=RHO_MODES)
    zone_m: float | None = option(
        None,
        "pool a demand history over square zones of this side, each at one node (default: the history's own, "
        "2000 m for a city's day; none per pair of nodes)",
        range=Range(50.0, 20_000.0, "m"),
    )
    accel: str = option(
        "anderson",
        "fixed-point acceleration (the same fixed point as the damped map, in about half the sweeps)",
        choices=ACCELERATIONS,
    )
    workers: int | None = option(
        None,
        "processes solving the hourly predictions side by side (default: the cores); the same predictions "
        "whatever the number",
        range=Range(1, 256, integer=True),
    )

    def predict_config(self) -> PredictConfig:
        """The prediction options that were set (the rest at :class:`PredictConfig`'s defaults)."""
        chosen = {
            k: getattr(self, k)
            for k in ("priority", "include_origin_state", "rho_mode")
            if getattr(self, k) is not None
        }
        return PredictConfig(accel=self.accel, **chosen)


#: The options of a strategy :class:`MBCalibrated` calibrates.
CalibratedOptionsT = TypeVar("CalibratedOptionsT", bound=CalibratedOptions)


def fraction(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` with ``0/0 := 0`` (§2.8)."""
    out = np.zeros(np.broadcast(num, den).shape)
    np.divide(num, den, out=out, where=den != 0)
    return out


class MBCalibrated:
    """τ_0 (A4) and l̄ from an MB run of the same scenario: FL's calibration, for any strategy whose options
    are :class:`CalibratedOptions` (FL, FL-no_delay, FL-perfect).  Listed before :class:`Strategy`."""

    calibrated_by: ClassVar[str | None] = "mb"

    @classmethod
    def needs_calibration(cls, options: CalibratedOptionsT) -> bool:
        return options.tau0_s is None or options.mean_pickup_m is None

    @classmethod
    def calibrate(
        cls, options: CalibratedOptionsT, kpis: dict[str, float], hourly: pd.DataFrame, hours: int
    ) -> CalibratedOptionsT:
        """τ_0 and l̄ from the MB run "for the same hour" (docs/algorithms.md §1-§2), per hour where the
        scenario spans several; options the user set are kept."""
        tau0: float | tuple[float, ...]
        pickup: float | tuple[float, ...]
        if hours == 1:
            tau0, pickup = kpis["avg_pickup_time_s"], kpis["avg_pickup_distance_m"]
        else:
            h = hourly.set_index("hour").reindex(range(hours))
            tau0 = tuple(round(float(x), 3) for x in h["avg_pickup_time_s"])
            pickup = tuple(round(float(x), 3) for x in h["avg_pickup_m"])
        return options.replace(
            tau0_s=tau0 if options.tau0_s is None else options.tau0_s,
            mean_pickup_m=pickup if options.mean_pickup_m is None else options.mean_pickup_m,
        )


class _ForwardBase(MBCalibrated, Strategy[ForwardOptions]):
    structure = Structure.ASSIGNMENT
    Options = ForwardOptions

    def __init__(self, options: ForwardOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.predictions: list[Prediction] = []
        self.mean_pickup_m: np.ndarray = np.array([FALLBACK_MEAN_PICKUP_M])
        #: Each node's representative when the predictions are per pair of zones (None: per pair of nodes).
        self.zone_node: np.ndarray | None = None

    # ----------------------------------------------------------- lookahead
    @property
    def clairvoyant(self) -> bool:
        """Rates counted from the scenario's own orders read the future."""
        return self.options.rates == "scenario"

    def clairvoyant_on(self, scenario: Scenario) -> bool:
        """``rates=auto`` counts the scenario's own orders too when it carries no demand history."""
        return self.clairvoyant or reads_realised_orders(self.options.rates, scenario.demand)

    # ----------------------------------------------------------- predictions
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
        tau0 = _per_hour(self.options.tau0_s, hours, FALLBACK_TAU0_S, "tau0_s")
        self.mean_pickup_m = _per_hour(self.options.mean_pickup_m, hours, FALLBACK_MEAN_PICKUP_M, "mean_pickup_m")
        zone = history_zone_m(self.options.rates, scenario.demand, self.options.zone_m)
        self.predictions = scenario_predictions(
            scenario, self.options.rates, tau0, self.options.predict_config(), zone, workers=self.options.workers
        )
        self.zone_node = None if zone is None else zone_representatives(scenario.network, zone)

    def predicted_od(self, state: RoundState) -> tuple[np.ndarray, np.ndarray]:
        """The waiting passengers' ODs as the predictions know them: their own, or their zones' representatives."""
        if self.zone_node is None:
            return state.p_origin, state.p_destination
        return self.zone_node[state.p_origin], self.zone_node[state.p_destination]

    def prediction_at(self, t_s: float) -> tuple[Prediction, int]:
        hour = min(int(t_s // 3600.0), len(self.predictions) - 1)
        return self.predictions[hour], hour

    def _options(self, state: RoundState) -> tuple[VacantOptions, JoinOptions, Prediction, int, np.ndarray]:
        vac, join = forward_options(state, self.options.order_rule)
        prediction, hour = self.prediction_at(state.t_s)
        e_vac = prediction.lookup(*self.predicted_od(state)).e_vacant
        return vac, join, prediction, hour, e_vac


class ForwardLooking(_ForwardBase):
    name = "fl"
    label = "FL"
    color = "tab:green"
    description = "forward-looking dispatch with intended delay, paper Eqs. (13)-(14)"

    def build(self, state: RoundState) -> RoundModel:
        vac, join, prediction, hour, e_vac = self._options(state)
        e_wait = prediction.e_wait(*self.predicted_od(state), state.p_rounds_waited, state.params)
        mean_pickup_m = float(self.mean_pickup_m[min(hour, len(self.mean_pickup_m) - 1)])
        return forward_round(state, vac, join, e_vac, e_wait, mean_pickup_m, name=self.name)


def forward_options(state: RoundState, order_rule: str) -> tuple[VacantOptions, JoinOptions]:
    """MB's options of the round, the joins only with a saving ``e > 0`` (A11)."""
    join = join_options(state, order_rule)
    return vacant_options(state), join.take(join.saving_m > 0)


def forward_round(
    state: RoundState,
    vac: VacantOptions,
    join: JoinOptions,
    e_vacant: np.ndarray,
    e_wait: np.ndarray,
    mean_pickup_m: float,
    *,
    name: str,
) -> RoundModel:
    """FL's round (Eqs. 13-14) from each waiting passenger's ē(p) and ē(0,p), whatever they come from
    (``join``: the options with ``e > 0``, A11)."""
    alpha_k = state.params.alpha ** state.p_rounds_waited.astype(np.float64)
    ev = e_vacant[vac.p]
    u_vac = fraction(ev * ev, ev + vac.pickup_m) * alpha_k[vac.p]
    e = join.saving_m
    u_join = fraction(e * e, e + join.pickup_m) * alpha_k[join.p]
    return assignment_round(state, vac, u_vac, join, u_join, e_wait - mean_pickup_m, name=name)


class ForwardLookingNoDelay(_ForwardBase):
    name = "fl-nd"
    label = "FL-no_delay"
    color = "tab:olive"
    description = "forward-looking dispatch without intended delay, paper Eq. (15)"

    def build(self, state: RoundState) -> RoundModel:
        vac, join, _, _, e_vac = self._options(state)
        return assignment_round(
            state,
            vac,
            e_vac[vac.p] - vac.pickup_m,
            join,
            join.saving_m - join.pickup_m,
            np.full(state.n_passengers, NO_WAIT_UTILITY_M),
            name=self.name,
        )


def _per_hour(value: float | tuple[float, ...] | None, hours: int, fallback: float, name: str) -> np.ndarray:
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
