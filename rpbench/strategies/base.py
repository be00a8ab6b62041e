"""What a dispatching strategy sees and what it returns.

The simulator knows a strategy only through :class:`Strategy`: once per
batch round it hands over a read-only :class:`RoundState` and gets back a
:class:`RoundModel` — a solver-agnostic model plus, per column, the decision
it stands for.  A strategy never calls a solver; the simulator solves the
model with the chosen preset and commits the chosen columns.  Adding a
formulation is therefore one new module with one class.
"""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Generic, TypeVar, cast

import numpy as np

from rpbench.model import AssignmentModel, Structure, TripPackingModel
from rpbench.scenarios.base import Params, Scenario
from rpbench.strategies.options import RunOptions

if TYPE_CHECKING:
    import pandas as pd

#: A strategy's options class (:attr:`Strategy.Options`).
OptionsT = TypeVar("OptionsT", bound=RunOptions)


class Kind(enum.IntEnum):
    """What a chosen column means."""

    WAIT = 0  # keep the passenger waiting for a later batch
    VACANT = 1  # a vacant vehicle (V0) picks the passenger up
    JOIN = 2  # the passenger joins a partially occupied vehicle (V1)
    TRIP2 = 3  # a vacant vehicle picks up two waiting passengers (RTV size-2 trip)


@dataclass(frozen=True, eq=False)
class RoundState:
    """A read-only snapshot of one batch round (arrays indexed per passenger / vehicle).

    Passengers are the waiting (revealed, unassigned, not cancelled) orders.
    ``V0`` are on-duty vacant vehicles at ``v0_pre_m`` metres before node
    ``v0_node`` (pick-up distance = pre + l(node, o_p)).  ``V1`` are on-duty
    vehicles with exactly one unpaired passenger A; the pair geometry of
    docs/algorithms.md §1.1 is ``h = v1_node``, ``δ = v1_delta_m``, ``pre =
    v1_pre_m`` (for A not yet picked up: h = o_A, δ = 0, pre = 0, A14).
    """

    t_s: float
    params: Params
    dist: np.ndarray  # all-pairs shortest distances (m)
    # waiting passengers
    p_order: np.ndarray  # scenario order index
    p_origin: np.ndarray
    p_destination: np.ndarray
    p_solo_m: np.ndarray
    p_request_s: np.ndarray
    p_rounds_waited: np.ndarray  # k_p = ceil((t - t_req) / Δt), >= 1 (A10)
    # vacant vehicles V0
    v0_vehicle: np.ndarray
    v0_node: np.ndarray
    v0_pre_m: np.ndarray
    # partially occupied vehicles V1
    v1_vehicle: np.ndarray
    v1_node: np.ndarray
    v1_delta_m: np.ndarray
    v1_pre_m: np.ndarray
    v1_order: np.ndarray  # passenger A's order index
    v1_origin: np.ndarray
    v1_destination: np.ndarray
    v1_solo_m: np.ndarray
    v1_onboard: np.ndarray  # bool: A already picked up

    @property
    def n_passengers(self) -> int:
        return len(self.p_order)

    @property
    def n_v0(self) -> int:
        return len(self.v0_vehicle)

    @property
    def n_v1(self) -> int:
        return len(self.v1_vehicle)


@dataclass(frozen=True, eq=False)
class RoundModel:
    """A strategy's model for one round and the decision behind each column.

    Per column: ``kind`` (:class:`Kind`), ``vehicle`` (simulator vehicle id,
    -1 for WAIT), ``first``/``second`` (order indices: the single passenger,
    or for TRIP2 the one picked up first and second; ``second = -1``
    otherwise), ``fofo`` (pairs: the passenger already in / picked up first
    is dropped first), ``utility_m`` (the unquantised value) and
    ``pickup_m`` (pick-up distance of the new passenger).
    """

    model: AssignmentModel | TripPackingModel
    kind: np.ndarray
    vehicle: np.ndarray
    first: np.ndarray
    second: np.ndarray
    fofo: np.ndarray
    utility_m: np.ndarray
    pickup_m: np.ndarray

    def __post_init__(self) -> None:
        n = self.model.n_cols
        for name in ("kind", "vehicle", "first", "second", "fofo", "utility_m", "pickup_m"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"RoundModel.{name} has {len(getattr(self, name))} entries for {n} columns")


class Strategy(ABC, Generic[OptionsT]):
    """A dispatching formulation: a subclass sets the class attributes and implements :meth:`build`.

    Everything the harness, the reports and the plots need to know about a
    strategy is a class attribute here, so adding one is one module plus one
    registry line.  A subclass with its own options names their class twice:
    as :attr:`Options` (read at run time) and as the type parameter
    (``class RTV(Strategy[RTVOptions])``), which types :attr:`options`.
    """

    name: ClassVar[str]
    structure: ClassVar[Structure]
    description: ClassVar[str] = ""
    #: Column header in tables and legend entry in plots.
    label: ClassVar[str]
    #: Matplotlib colour of its line in plots (None: the next colour of the cycle).
    color: ClassVar[str | None] = None
    #: Its options, declared once (names, types, defaults, help).
    Options: ClassVar[type[RunOptions]] = RunOptions
    #: The strategy whose run on the same scenario calibrates this one (None: none needed).
    calibrated_by: ClassVar[str | None] = None

    def __init__(self, options: OptionsT | None = None, **raw: Any):
        """Options as a parsed :attr:`Options` object, or as keyword values (parsed and checked here)."""
        if options is not None and raw:
            raise TypeError("give options either parsed or as keywords, not both")
        parsed = options if options is not None else self.Options.parse(self.name, raw)
        if not isinstance(parsed, self.Options):
            raise TypeError(f"{self.name}: options must be {self.Options.__name__}, not {type(parsed).__name__}")
        # Options is the class the type parameter names; a ClassVar cannot carry the parameter itself
        self.options: OptionsT = cast(OptionsT, parsed)

    @classmethod
    def needs_calibration(cls, options: OptionsT) -> bool:
        """Whether ``options`` still lack what the :attr:`calibrated_by` run provides."""
        return cls.calibrated_by is not None

    @classmethod
    def calibrate(cls, options: OptionsT, kpis: dict[str, float], hourly: pd.DataFrame, hours: int) -> OptionsT:
        """``options`` completed from the calibration run's KPIs (whole run) and ``hourly`` table."""
        return options

    def prepare(self, scenario: Scenario) -> None:
        """Called once before the first round (e.g. to load predictions)."""

    @abstractmethod
    def build(self, state: RoundState) -> RoundModel:
        """Build the model of the batch round the state describes."""

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vehicles to send towards nodes after the round's decisions (default: none).

        Returns ``(vehicle ids, target nodes)``; a repositioned vehicle stays
        vacant and resumes cruising when it arrives.
        """
        return np.zeros(0, np.int64), np.zeros(0, np.int64)

    def describe(self) -> dict[str, Any]:
        """Options as recorded in a results folder's meta.json."""
        return {"name": self.name, "structure": self.structure.value, "options": self.options.as_dict()}
