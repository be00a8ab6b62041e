"""Scenario = orders + fleet + parameters on a road network (frozen, validated), and its online view.

Generators that build scenarios from the Haikou data or in code live in
:mod:`rpbench.scenarios`; this module only defines the objects.  Units are in
the names (``_s`` seconds from the scenario start, ``_m`` metres).  All
defaults are the paper's (§4.1): Δt = 10 s, R̄ = D̄ = 3000 m, 30 km/h,
α = 1.01, r_w = 0.75, patience ~ N(90 s, 10 s) floored at 30 s, fares 5 and
3.5 CNY/km, drivers paid 2 CNY/km, 25 vehicles per 100 orders.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rpbench.exceptions import LookaheadError, ParameterError
from rpbench.network import RoadNetwork

#: The scenario summary's count of zero-length orders (origin = destination node after snapping): served solo,
#: never pooled (docs/simulator.md); the checker applies that rule to folders that record it.
ZERO_LENGTH_KEY = "zero_length_orders"


@dataclass(frozen=True)
class Params:
    """Simulation and dispatch parameters (the paper's defaults).

    Every value must be a finite number within sane physical bounds (an
    absurd value otherwise gives garbage or a run that never ends: Δt = 1e-9 s
    means 3.6e12 rounds per hour, a speed of 1e-300 m/s infinite travel times):

    ===========================================  ================  ==================
    parameter                                    range             paper's default
    ===========================================  ================  ==================
    ``dt_s`` (Δt)                                [0.1, 3600] s     10 s
    ``speed_mps``                                [0.1, 100] m/s    8.33 m/s (30 km/h)
    ``max_pickup_m``, ``max_detour_m``           (0, 1e6] m        3000 m
    ``planner_patience_s``, ``patience_mean_s``  [1, 86400] s      90 s
    ``patience_sd_s``, ``patience_floor_s``      [0, 86400] s      10 s, 30 s
    ``alpha`` (α)                                (0, 10]           1.01
    ``response_rate`` (r_w)                      [0, 1]            0.75
    ``vehicles_per_100_orders``                  (0, 1000]         25
    fares and driver pay                         [0, 1000] CNY/km  5, 3.5, 2
    ===========================================  ================  ==================

    R̄ and D̄ have no lower bound beyond > 0: a tiny tolerance is meaningful
    ("no detour at all") and harmless.  The sweeps (Δt 2-60 s, K 60-600 s,
    r_w 0.1-0.9, ratio 10-25) lie well inside.
    """

    dt_s: float = 10.0  # Δt, batch interval
    max_pickup_m: float = 3000.0  # R̄
    max_detour_m: float = 3000.0  # D̄
    speed_mps: float = 30.0 / 3.6  # constant vehicle speed (30 km/h)
    alpha: float = 1.01  # FL waiting-priority base α (Eq. 13)
    response_rate: float = 0.75  # r_w, presumed per-round response rate (Eq. 10)
    planner_patience_s: float = 90.0  # K̄, the patience the planner assumes (A10)
    patience_mean_s: float = 90.0  # K_p ~ N(mean, sd), floored
    patience_sd_s: float = 10.0
    patience_floor_s: float = 30.0
    vehicles_per_100_orders: float = 25.0  # order-driver ratio 100:25
    fare_solo_cny_per_km: float = 5.0
    fare_pooled_cny_per_km: float = 3.5
    driver_pay_cny_per_km: float = 2.0

    _POSITIVE = (
        "dt_s",
        "max_pickup_m",
        "max_detour_m",
        "speed_mps",
        "planner_patience_s",
        "patience_mean_s",
        "vehicles_per_100_orders",
    )
    _NON_NEGATIVE = (
        "patience_sd_s",
        "patience_floor_s",
        "fare_solo_cny_per_km",
        "fare_pooled_cny_per_km",
        "driver_pay_cny_per_km",
    )
    #: Upper bounds (and, where above 0, lower bounds) of the class docstring's table: name -> (low, high, unit).
    _RANGE: ClassVar[dict[str, tuple[float, float, str]]] = {
        "dt_s": (0.1, 3600.0, "s"),
        "speed_mps": (0.1, 100.0, "m/s"),
        "max_pickup_m": (0.0, 1e6, "m"),
        "max_detour_m": (0.0, 1e6, "m"),
        "planner_patience_s": (1.0, 86400.0, "s"),
        "patience_mean_s": (1.0, 86400.0, "s"),
        "patience_sd_s": (0.0, 86400.0, "s"),
        "patience_floor_s": (0.0, 86400.0, "s"),
        "alpha": (0.0, 10.0, ""),
        "vehicles_per_100_orders": (0.0, 1000.0, ""),
        "fare_solo_cny_per_km": (0.0, 1000.0, "CNY/km"),
        "fare_pooled_cny_per_km": (0.0, 1000.0, "CNY/km"),
        "driver_pay_cny_per_km": (0.0, 1000.0, "CNY/km"),
    }

    def __post_init__(self) -> None:
        for name in self._POSITIVE + self._NON_NEGATIVE + ("alpha", "response_rate"):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float, np.floating, np.integer))
                or not np.isfinite(value)
            ):
                raise ParameterError(f"parameter {name} = {value!r} is not a finite number")
        for name in self._POSITIVE:
            if getattr(self, name) <= 0:
                raise ParameterError(f"parameter {name} = {getattr(self, name)!r} must be > 0")
        for name in self._NON_NEGATIVE:
            if getattr(self, name) < 0:
                raise ParameterError(f"parameter {name} = {getattr(self, name)!r} must be >= 0")
        if self.alpha <= 0:
            raise ParameterError(f"parameter alpha = {self.alpha!r} must be > 0 (the paper uses 1.01)")
        if not 0 <= self.response_rate <= 1:
            raise ParameterError(f"parameter response_rate = {self.response_rate!r} must lie in [0, 1]")
        self._check_ranges()

    def _check_ranges(self) -> None:
        """The sane physical bounds (signs are checked before, with their own messages)."""
        for name, (low, high, unit) in self._RANGE.items():
            value = getattr(self, name)
            if value < low or value > high:
                strict = low == 0 and (name in self._POSITIVE or name == "alpha")  # (0, high]
                raise ParameterError(
                    f"parameter {name} = {value!r} is outside its sane range "
                    f"{'(' if strict else '['}{low:g}, {high:g}]{' ' + unit if unit else ''} "
                    f"(the paper uses {getattr(Params, name):g})"
                )

    def replace(self, **changes: Any) -> Params:
        """A copy with some fields changed (validated); unknown names are an error."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise ParameterError(
                f"unknown parameter(s) {', '.join(sorted(unknown))}; "
                f"known: {', '.join(f.name for f in dataclasses.fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)


@dataclass(frozen=True, eq=False)
class Orders:
    """Ride requests sorted by request time (node indices are the network's internal ones)."""

    order_id: np.ndarray  # int64, unique
    request_s: np.ndarray  # float64, seconds from scenario start, non-decreasing
    origin: np.ndarray  # int32 node index
    destination: np.ndarray  # int32 node index
    patience_s: np.ndarray  # float64, K_p > 0

    def __post_init__(self) -> None:
        n = len(self.order_id)
        for name in ("request_s", "origin", "destination", "patience_s"):
            if len(getattr(self, name)) != n:
                raise ParameterError(f"orders: column {name} has {len(getattr(self, name))} rows, expected {n}")
        if n and np.any(np.diff(self.request_s) < 0):
            raise ParameterError("orders must be sorted by request time")
        if n and (not np.all(np.isfinite(self.request_s)) or np.any(self.patience_s <= 0)):
            raise ParameterError("orders: request times must be finite and patience positive")
        if len(np.unique(self.order_id)) != n:
            raise ParameterError("orders: order ids are not unique")

    def __len__(self) -> int:
        return len(self.order_id)


@dataclass(frozen=True, eq=False)
class Fleet:
    """Vehicles and how many are on duty over time.

    ``online_times_s``/``online_count`` define a step function: from
    ``online_times_s[k]`` on, vehicles ``0..online_count[k]-1`` are on duty.
    A vehicle that goes off duty finishes its passengers first.  ``None``
    means every vehicle is on duty all the time.
    """

    initial_node: np.ndarray  # int32 node index per vehicle
    online_times_s: np.ndarray | None = None  # float64, increasing, first = 0
    online_count: np.ndarray | None = None  # int64, <= number of vehicles

    def __post_init__(self) -> None:
        times, count = self.online_times_s, self.online_count
        if times is None or count is None:
            if times is not None or count is not None:
                raise ParameterError("fleet: online_times_s and online_count go together")
            return
        if len(times) != len(count) or len(count) == 0:
            raise ParameterError("fleet: online schedule arrays differ in length or are empty")
        if np.any(np.diff(times) <= 0) or times[0] != 0:
            raise ParameterError("fleet: online_times_s must start at 0 and increase")
        if np.any(count < 0) or np.any(count > len(self.initial_node)):
            raise ParameterError("fleet: online_count must lie in [0, number of vehicles]")

    def __len__(self) -> int:
        return len(self.initial_node)

    def on_duty(self, t_s: float) -> int:
        """Number of vehicles on duty at time ``t_s`` (vehicles 0..n-1)."""
        if self.online_times_s is None or self.online_count is None:  # both or neither (__post_init__)
            return len(self.initial_node)
        k = int(np.searchsorted(self.online_times_s, t_s, side="right")) - 1
        return int(self.online_count[max(k, 0)])


@dataclass(frozen=True, eq=False)
class History:
    """Orders of ``days`` past days of the scenario's demand, as a dispatcher has seen them before the day.

    Per order its request time within its day (seconds from the day's start) and its OD (node indices);
    the rates it implies are count / (``days`` x 3600 s) per OD and hour.  ``source`` says where it comes
    from (one line, no machine path).
    """

    request_s: np.ndarray  # float64
    origin: np.ndarray  # int32 node index
    destination: np.ndarray  # int32 node index
    days: int
    source: str
    #: Too sparse to count per pair of nodes: pool its rates over square zones of this side (m), each zone
    #: standing for its nodes through one of them (:mod:`rpbench.predict.zones`); None: per pair of nodes.
    zone_m: float | None = None

    def __post_init__(self) -> None:
        n = len(self.request_s)
        if len(self.origin) != n or len(self.destination) != n:
            raise ParameterError(f"demand history: {n} request times for {len(self.origin)} origins")
        if self.days < 1:
            raise ParameterError(f"demand history: {self.days} days; at least one")


@dataclass(frozen=True)
class Demand:
    """The demand rates λ_w known before the day (what FL's prediction, paper §3.1, is fed by default).

    ``table = "month"``: the 21-day 08:00-09:00 OD rate table of ``data_dir``
    (the paper's λ_w); with ``orders_per_hour`` it is scaled so that hour h
    carries that many orders (how the synthetic full day draws its demand).
    ``table = "history"``: past days of the same demand, ``history`` (a generated
    city: its generator's draws at other seeds).  ``table = None``: no history;
    only the scenario's own orders, the realisation, which an online strategy
    cannot read (:class:`~rpbench.scenarios.base.OnlineView`).
    """

    table: str | None = None
    data_dir: str | None = None
    orders_per_hour: tuple[float, ...] | None = None
    history: History | None = None

    def __post_init__(self) -> None:
        if (self.table == "history") != (self.history is not None):
            raise ParameterError("demand: table 'history' and a history go together")


@dataclass(frozen=True, eq=False)
class Scenario:
    """A complete, reproducible simulation input."""

    name: str  # generator name, e.g. "haikou-peak"
    label: str  # one line shown wherever results are shown
    network: RoadNetwork
    orders: Orders
    fleet: Fleet
    params: Params
    seed: int
    horizon_s: float  # simulated period [0, horizon_s)
    start_time: str  # ISO date-time of t = 0 (for display)
    synthetic: bool  # True for stand-ins and generated cities
    provenance: dict = field(default_factory=dict)
    demand: Demand = Demand()

    def __post_init__(self) -> None:
        n = self.network.n_nodes
        for name in ("origin", "destination"):
            arr = getattr(self.orders, name)
            if len(arr) and (arr.min() < 0 or arr.max() >= n):
                raise ParameterError(f"orders: {name} node index outside the network (0..{n - 1})")
        if len(self.fleet) and (self.fleet.initial_node.min() < 0 or self.fleet.initial_node.max() >= n):
            raise ParameterError(f"fleet: initial node outside the network (0..{n - 1})")
        if self.horizon_s <= 0:
            raise ParameterError(f"horizon_s = {self.horizon_s} must be > 0")

    def online_view(self, reader: str | None = None) -> OnlineView:
        """What an online dispatcher knows before the day: everything but the orders (``reader``: who holds it,
        named by the :class:`~rpbench.exceptions.LookaheadError` a read of the orders raises)."""
        return OnlineView.of(self, reader)

    def summary(self) -> dict[str, Any]:
        """The facts ``rpbench scenario`` prints (keys ``orders``, ``vehicles``, ``nodes`` are stable)."""
        o = self.orders
        solo = self.network.distances()(o.origin, o.destination) if len(o) else np.zeros(0)
        od = np.unique(o.origin.astype(np.int64) * self.network.n_nodes + o.destination) if len(o) else np.zeros(0)
        return {
            "scenario": self.name,
            "label": self.label,
            "synthetic": self.synthetic,
            "orders": len(o),
            "vehicles": len(self.fleet),
            "nodes": int(self.network.n_nodes),
            "arcs": int(self.network.n_arcs),
            "distinct_od_pairs": len(od),
            ZERO_LENGTH_KEY: int((solo <= 0).sum()),
            "mean_solo_trip_m": float(solo.mean()) if len(o) else 0.0,
            "first_request_s": float(o.request_s[0]) if len(o) else 0.0,
            "last_request_s": float(o.request_s[-1]) if len(o) else 0.0,
            "horizon_s": float(self.horizon_s),
            "start_time": self.start_time,
            "seed": int(self.seed),
            "network": self.network.name,
            "data_source": self.provenance.get("source", ""),
            "params": self.params.as_dict(),
        }


# ------------------------------------------------------------------ what an online dispatcher sees
#: Attributes of a :class:`Scenario` that hold or are computed from its realised orders.
REALISED = ("orders", "summary")

LOOKAHEAD_HINT = (
    "online strategies see orders only as they are revealed in RoundState; declare `clairvoyant = True` to read "
    "the future"
)


@dataclass(frozen=True, eq=False)
class OnlineView:
    """A :class:`Scenario` without its realised orders (frozen; ``provenance`` is a copy).

    What the simulator hands an online strategy's ``prepare`` (a strategy declaring ``clairvoyant`` gets
    the whole :class:`Scenario`): the road network, the fleet, the parameters, the seed, the horizon, the
    labels and provenance, and the demand *history* (:class:`Demand`: the 21-day OD table, or past days of
    a generator), but not the orders, which reach a strategy only as the simulator reveals them in each
    round's ``RoundState``.  Reaching for them raises one :class:`~rpbench.exceptions.LookaheadError` line
    naming the strategy.  The view has no ``orders`` attribute at all, so mypy also flags code that reads
    them from a ``Scenario | OnlineView`` without first asking which it holds.

    ``reader`` names who holds the view (``strategy 'mine' (mymod.Mine)``), for the error line.
    """

    name: str
    label: str
    network: RoadNetwork
    fleet: Fleet
    params: Params
    seed: int
    horizon_s: float
    start_time: str
    synthetic: bool
    provenance: dict[str, Any]
    demand: Demand
    reader: str = "an online strategy"

    @classmethod
    def of(cls, scenario: Scenario, reader: str | None = None) -> OnlineView:
        """The view of ``scenario`` (``reader``: who will hold it)."""
        return cls(
            name=scenario.name,
            label=scenario.label,
            network=scenario.network,
            fleet=scenario.fleet,
            params=scenario.params,
            seed=scenario.seed,
            horizon_s=scenario.horizon_s,
            start_time=scenario.start_time,
            synthetic=scenario.synthetic,
            provenance=dict(scenario.provenance),  # a copy: the scenario's stays as it is
            demand=scenario.demand,
            reader=reader or cls.reader,
        )

    def refusal(self, name: str = "orders") -> LookaheadError:
        """The error a read of ``name`` raises (for code that checks ``isinstance`` first: ``raise view.refusal()``)."""
        return LookaheadError(f"{self.reader} read the scenario's {name} before they were revealed: {LOOKAHEAD_HINT}")

    if not TYPE_CHECKING:  # at run time only: mypy keeps flagging a read of a view's orders

        def __getattr__(self, name: str) -> Any:
            if name in REALISED:
                raise self.refusal(name)
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
