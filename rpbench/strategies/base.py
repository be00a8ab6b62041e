"""What a dispatching strategy sees and what it returns.

The simulator knows a strategy only through :class:`Strategy`: once before
the first round it hands :meth:`Strategy.prepare` what is known before the day
(an :class:`~rpbench.scenarios.base.OnlineView`, the scenario without its
orders; the whole scenario only to a strategy that declares itself
:attr:`~Strategy.clairvoyant`), then once per batch round a read-only
:class:`RoundState`, and it gets back a :class:`RoundModel` — a
solver-agnostic model plus, per column, the decision it stands for.  A
strategy never calls a solver; the simulator solves the model with the chosen
preset and commits the chosen columns.  Adding a formulation is therefore one
new module with one class.
"""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Generic, TypeVar, cast

import numpy as np
from numba import njit

from rpbench.exceptions import ModelError, one_line
from rpbench.model import AssignmentModel, Structure, TripPackingModel
from rpbench.model.kernels import read_only
from rpbench.options import RunOptions
from rpbench.scenarios.base import OnlineView, Params, Scenario

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
                raise ModelError(f"RoundModel.{name} has {len(getattr(self, name))} entries for {n} columns")


#: The model class of each round structure (exactly: a subclass could redefine what its columns cover).
ROUND_MODELS: dict[Structure, type] = {Structure.ASSIGNMENT: AssignmentModel, Structure.TRIP_PACKING: TripPackingModel}


def received(rm: object, state: RoundState, structure: Structure) -> RoundModel:
    """What :meth:`Strategy.build` returned, checked against its round and copied into read-only arrays.

    Validation on construction is not enough: a strategy may change its arrays afterwards.  The
    copy (the one the solver and the simulator use) is checked as it is: a :class:`RoundModel`
    around the structure's model class, the model valid (:meth:`~rpbench.model._Model.frozen`),
    its rows the round's waiting passengers and then its V0 and V1 vehicles in state order, and
    each column's decoding the decision its model column stands for.  A model the solver finds
    feasible is then a set of decisions the simulator can commit.  Raises one :class:`ModelError`
    line saying what is wrong (the caller names the strategy).
    """
    if not isinstance(rm, RoundModel):
        raise ModelError(f"build() returned {_a(rm)}, not a RoundModel")
    want = ROUND_MODELS.get(structure)
    if want is None or type(rm.model) is not want:
        expected = {Structure.ASSIGNMENT: "an AssignmentModel", Structure.TRIP_PACKING: "a TripPackingModel"}.get(
            structure, "an AssignmentModel or a TripPackingModel"
        )
        raise ModelError(
            f"build() returned a RoundModel around {_a(rm.model)}; a strategy of structure {structure.value} "
            f"returns {expected}"
        )
    try:
        model = rm.model.frozen()
        checked = RoundModel(
            model=model,
            kind=_frozen(rm.kind, "RoundModel.kind", np.int8, model.n_cols),
            vehicle=_frozen(rm.vehicle, "RoundModel.vehicle", np.int64, model.n_cols),
            first=_frozen(rm.first, "RoundModel.first", np.int64, model.n_cols),
            second=_frozen(rm.second, "RoundModel.second", np.int64, model.n_cols),
            fofo=_frozen(rm.fofo, "RoundModel.fofo", np.bool_, model.n_cols),
            utility_m=_frozen(rm.utility_m, "RoundModel.utility_m", np.float64, model.n_cols),
            pickup_m=_frozen(rm.pickup_m, "RoundModel.pickup_m", np.float64, model.n_cols),
        )
        _check_decoding(checked, state)
    except ModelError as exc:
        raise ModelError(f"build() returned an invalid model: {exc}") from None
    except (TypeError, ValueError, AttributeError, IndexError) as exc:  # arrays of the wrong kind
        raise ModelError(f"build() returned a malformed model ({type(exc).__name__}: {one_line(exc)})") from None
    return checked


def _a(obj: object) -> str:
    return "None" if obj is None else f"a {type(obj).__name__}"


def _frozen(raw: object, name: str, dtype: type, n: int | None = None) -> np.ndarray:
    """A read-only copy of ``raw`` as ``dtype`` (``n`` entries), refusing a cast that would change its values."""
    if type(raw) is np.ndarray and raw.dtype == dtype and raw.ndim == 1 and (n is None or len(raw) == n):
        same = raw.copy()  # the usual case: already as wanted, nothing to check
        same.setflags(write=False)
        return same
    arr = np.array(raw)
    if arr.ndim != 1 or (n is not None and len(arr) != n):
        raise ModelError(f"{name} has shape {arr.shape}" + (f" for {n} columns" if n is not None else ""))
    if len(arr) and arr.dtype.kind not in ("b" if dtype is np.bool_ else "biuf"):
        raise ModelError(f"{name} holds {arr.dtype} values")
    out: np.ndarray = arr.astype(dtype, copy=False)  # np.array copied it already
    if out is not arr and dtype is not np.float64 and not np.array_equal(out, arr):  # NaN, 1.5, 300 as int8
        c = int(np.flatnonzero(out != arr)[0])
        raise ModelError(f"{name}[{c}] = {arr[c].item()!r} is not a valid {np.dtype(dtype).name}")
    out.setflags(write=False)
    return out


def received_moves(
    moves: object, state: RoundState, assigned: np.ndarray, n_nodes: int
) -> tuple[np.ndarray, np.ndarray]:
    """What :meth:`Strategy.reposition` returned, checked: distinct vacant vehicles of the round that
    were not just assigned (``assigned``: their ids), each sent to a node index of the network."""
    try:
        raw_vehicles, raw_targets = cast(tuple[object, object], moves)
    except (TypeError, ValueError):
        raise ModelError(f"reposition() returned {_a(moves)}, not a pair (vehicle ids, target nodes)") from None
    vehicles = _frozen(raw_vehicles, "reposition() vehicles", np.int64)
    targets = _frozen(raw_targets, "reposition() targets", np.int64, len(vehicles))
    if not len(vehicles):
        return vehicles, targets
    ordered = np.sort(vehicles)
    for bad, why in (
        (vehicles[~np.isin(vehicles, state.v0_vehicle)], "is not a vacant vehicle of the round"),
        (vehicles[np.isin(vehicles, assigned)], "was assigned a passenger in the same round"),
        (ordered[1:][ordered[1:] == ordered[:-1]], "is sent twice"),
    ):
        if len(bad):
            raise ModelError(f"reposition() vehicle {int(bad[0])} {why}")
    bad = np.flatnonzero((targets < 0) | (targets >= n_nodes))
    if len(bad):
        raise ModelError(f"reposition() target node {int(targets[bad[0]])} is not a node index (0..{n_nodes - 1})")
    return vehicles, targets


_KIND_NAMES = {int(k): k.name for k in Kind}


def _check_decoding(rm: RoundModel, state: RoundState) -> None:
    """Each column's (kind, vehicle, first, second) is the decision its model column stands for.

    One pass over all columns with few numpy calls (a simulation round has tens of columns, so each
    call's overhead is what counts); only a failing model pays for finding out what is wrong.
    """
    model = rm.model
    if isinstance(model, AssignmentModel):
        passengers, row_vehicle, r1, r2 = model.n_passengers, model.col_vehicle, model.col_passenger, None
    else:  # received() passes only the two round models
        passengers, row_vehicle, r1, r2 = model.n_requests, model.col_vehicle, model.col_request1, model.col_request2
    n_vehicles = state.n_v0 + state.n_v1
    if passengers > state.n_passengers or model.n_vehicles > n_vehicles:
        raise ModelError(
            f"the model has {passengers} passenger and {model.n_vehicles} vehicle rows for a round of "
            f"{state.n_passengers} waiting passengers and {n_vehicles} vehicles (V0 then V1)"
        )
    if r2 is None and _assignment_decoded(
        rm.kind, rm.vehicle, rm.first, rm.second, rm.utility_m, rm.pickup_m, row_vehicle, r1,
        state.v0_vehicle, state.v1_vehicle, state.p_order,
    ):  # fmt: skip
        return  # every column as below, in one compiled pass; the numpy passes find what is wrong
    # the decision of each column; index -1 (keep waiting, no second request) reads the appended -1
    vehicle = np.concatenate([state.v0_vehicle, state.v1_vehicle, [-1]])[row_vehicle]
    kind = (row_vehicle >= state.n_v0).astype(np.int8) + np.int8(Kind.VACANT)  # VACANT or JOIN
    kind[row_vehicle < 0] = Kind.WAIT
    a = state.p_order[r1]
    finite = np.isfinite(rm.utility_m + rm.pickup_m) | (row_vehicle < 0)
    if r2 is None:
        ok = (rm.kind == kind) & (rm.vehicle == vehicle) & (rm.first == a) & (rm.second == -1) & finite
    else:
        pair = r2 >= 0
        kind[pair] = Kind.TRIP2
        b = np.append(state.p_order, -1)[r2]
        orders = ((rm.first == a) & (rm.second == b)) | (pair & (rm.first == b) & (rm.second == a))
        v0 = ~pair | (row_vehicle < state.n_v0)  # a two-request trip takes a vacant vehicle
        ok = (rm.kind == kind) & (rm.vehicle == vehicle) & orders & v0 & finite
    if not ok.all():
        _explain(rm, state, int(np.flatnonzero(~ok)[0]), kind, vehicle, a, None if r2 is None else b)


@njit(cache=True, nogil=True)
def _assignment_decoded(
    kind, vehicle, first, second, utility, pickup, row_vehicle, row_passenger, v0_vehicle, v1_vehicle, p_order
) -> bool:  # pragma: no cover - compiled
    """Whether every column of an assignment round decodes as :func:`_check_decoding` requires."""
    n_v0 = len(v0_vehicle)
    for c in range(len(kind)):
        row = row_vehicle[c]
        if row < 0:
            want_kind, want_vehicle = 0, -1  # Kind.WAIT
        elif row < n_v0:
            want_kind, want_vehicle = 1, v0_vehicle[row]  # Kind.VACANT
        else:
            want_kind, want_vehicle = 2, v1_vehicle[row - n_v0]  # Kind.JOIN
        if kind[c] != want_kind or vehicle[c] != want_vehicle or first[c] != p_order[row_passenger[c]]:
            return False
        if second[c] != -1 or not (row < 0 or np.isfinite(utility[c] + pickup[c])):
            return False
    return True


def load_state_kernels() -> None:
    """Load (or compile) the decoding check now: its first call costs a one-off load of its machine code."""
    i, f = np.zeros(0, np.int64), np.zeros(0)
    _assignment_decoded(np.zeros(0, np.int8), i, i, i, f, f, np.zeros(0, np.int32), np.zeros(0, np.int32), i, i, i)
    # as received() calls it: the round model's arrays are read-only copies
    ro = [read_only(np.zeros(0, d)) for d in (np.int8, np.int64, np.int64, np.int64, float, float, np.int32, np.int32)]
    _assignment_decoded(ro[0], ro[1], ro[2], ro[3], ro[4], ro[5], ro[6], ro[7], i, i, i)


def _explain(
    rm: RoundModel, state: RoundState, c: int, kind: np.ndarray, vehicle: np.ndarray, a: np.ndarray, b
) -> None:
    """Raise the :class:`ModelError` saying what is wrong with column ``c`` (its expected decision given)."""
    row = int(rm.model.col_vehicle[c])
    pair = b is not None and b[c] >= 0
    want = Kind(int(kind[c]))
    if int(rm.kind[c]) != want:
        what = {
            Kind.WAIT: "keeps its passenger waiting",
            Kind.TRIP2: "is a two-passenger trip",
            Kind.VACANT: "is a vacant vehicle's (a V0 row)",
            Kind.JOIN: "is a partly occupied vehicle's (a V1 row)",
        }[want]
        got = _KIND_NAMES.get(int(rm.kind[c]), str(int(rm.kind[c])))
        raise ModelError(f"column {c} has kind {got}, but its model column {what}: kind {want.name}")
    if pair and row >= state.n_v0:
        raise ModelError(
            f"column {c} is a two-passenger trip of a partly occupied vehicle (vehicle row {row}); "
            "only a vacant vehicle may take one"
        )
    if int(rm.vehicle[c]) != int(vehicle[c]):
        raise ModelError(
            f"column {c} has vehicle {int(rm.vehicle[c])}, but its model column stands for vehicle {int(vehicle[c])}"
            + (" (-1: keep waiting)" if row < 0 else f" (vehicle row {row}: V0 then V1 in state order)")
        )
    first, second = int(rm.first[c]), int(rm.second[c])
    orders = (int(a[c]), int(b[c]) if b is not None else -1)
    if (first, second) != orders and not (pair and (second, first) == orders):
        serves = f"orders {orders[0]} and {orders[1]}" if pair else f"order {orders[0]}"
        raise ModelError(
            f"column {c} has (first, second) = ({first}, {second}), but its model column "
            f"serves {serves} (passenger rows are the round's waiting passengers in state order)"
        )
    raise ModelError(
        f"column {c} has utility_m {float(rm.utility_m[c])!r} and pickup_m {float(rm.pickup_m[c])!r}; "
        "a column that assigns a passenger needs finite ones"
    )


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
    #: The policy whose simulated runs on training scenarios teach this strategy its value model (None: it
    #: learns none); the harness trains it before the run (:mod:`rpbench.harness.training`).
    trained_by: ClassVar[str | None] = None

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

    @property
    def clairvoyant(self) -> bool:
        """Whether the strategy reads the future: its :meth:`prepare` gets the whole scenario, orders included,
        and its run is marked clairvoyant in meta.json and wherever it is shown or ranked.  A strategy that does
        declares ``clairvoyant = True`` in its class body; one that does under some options only, a property."""
        return False

    def clairvoyant_on(self, scenario: Scenario) -> bool:
        """Whether this run on ``scenario`` reads the future (default: :attr:`clairvoyant`); for a strategy whose
        options read the future on some scenarios only (FL's ``rates=auto`` on one without demand history)."""
        return self.clairvoyant

    def prepare(self, scenario: Scenario | OnlineView) -> None:
        """Called once before the first round (e.g. to load predictions), with what is known before the day.

        An online strategy gets an :class:`~rpbench.scenarios.base.OnlineView` (no orders: reading them raises
        :class:`~rpbench.exceptions.LookaheadError`); a :attr:`clairvoyant` one the whole :class:`Scenario`.
        """

    @abstractmethod
    def build(self, state: RoundState) -> RoundModel:
        """Build the model of the batch round the state describes."""

    def finish(self) -> None:
        """Called once when the run ends, after its last round or when it stops early (default: nothing):
        where a strategy lets go of what it holds (a dispatcher program it started, say)."""

    def artefacts(self) -> dict[str, tuple[str, Path]]:
        """Files the run's decisions depend on, by name: ``(digest, folder)`` (default: none).

        Called after the run; each folder is copied into the run's results folder under its name and
        its digest recorded in meta.json, so that ``rpbench check`` can verify it (a learned model, say).
        """
        return {}

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vehicles to send towards nodes after the round's decisions (default: none).

        Returns ``(vehicle ids, target nodes)``; a repositioned vehicle stays
        vacant and resumes cruising when it arrives.
        """
        return np.zeros(0, np.int64), np.zeros(0, np.int64)

    def idle_moves(self, state: RoundState) -> tuple[np.ndarray, np.ndarray]:
        """Vehicles to send towards nodes in a round where nobody waits (no model is built then; default:
        none).  The simulator builds such a round's state only for a strategy that overrides this.

        Returns ``(vehicle ids, target nodes)`` of vacant vehicles, as :meth:`reposition`.
        """
        return np.zeros(0, np.int64), np.zeros(0, np.int64)

    def describe(self) -> dict[str, Any]:
        """Options as recorded in a results folder's meta.json."""
        return {
            "name": self.name,
            "structure": self.structure.value,
            "options": self.options.as_dict(),
            "clairvoyant": self.clairvoyant,
        }
