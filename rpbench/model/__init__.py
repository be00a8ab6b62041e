"""Solver-agnostic decision models: 0/1 set packing over a sparse incidence matrix (frozen to instance
files by :mod:`.instances`).

Every decision rpbench makes is one of three models, each

    maximise  Σ_c values[c] · x[c]
    s.t.      Σ_{c covers r} x[c] = 1   for rows r with ``row_exact[r]``
              Σ_{c covers r} x[c] ≤ 1   for the other rows
              x ∈ {0, 1}

with a special structure exact algorithms exploit:

* :class:`AssignmentModel` — one batch round (paper Eqs. 1-4 and 14): rows are
  passengers (exactly one option each) and vehicles (at most one passenger);
  a column is (passenger, vehicle) or (passenger, keep waiting).  Bipartite,
  so the LP relaxation is integral.
* :class:`TripPackingModel` — RTV's trip assignment (docs/algorithms.md §3.3):
  a column is (trip of one or two requests, vehicle); each request and each
  vehicle at most once.  General set packing.
* :class:`PairingModel` — the oracle (docs/algorithms.md §4): a column is a pair
  of orders; each order at most once.  General-graph matching: odd cycles
  make the LP relaxation fractional (the unit triangle has LP value 1.5).
  ``objective = "cardinality_then_weight"`` asks for a maximum-cardinality
  matching of maximum weight (Oracle-2, A20).

Values are integers in units of ``unit_m`` metres (default 1 mm), so every
exact backend — including integer-only algorithms — solves the *same*
problem and objectives can be compared exactly.  Use :func:`quantize` to turn
metres into model values.  Models are frozen and validated on construction.
"""

from __future__ import annotations

import copy
import enum
import math
from dataclasses import dataclass, field, fields
from typing import ClassVar, Self

import numpy as np
import scipy.sparse as sp

from rpbench.exceptions import ModelError, SolverError

#: Sums of |values| must stay exactly representable in float64 (2**53).
MAX_EXACT_TOTAL = float(2**53)
_INT32 = np.iinfo(np.int32)


class Structure(str, enum.Enum):  # noqa: UP042 (str() of a str-mixin enum stays the member name)
    ASSIGNMENT = "assignment"
    TRIP_PACKING = "trip_packing"
    PAIRING = "pairing"


class Status(str, enum.Enum):  # noqa: UP042 (as Structure)
    OPTIMAL = "optimal"  # proven optimal
    FEASIBLE = "feasible"  # feasible, stopped with a gap (gap/bound say how far)
    TIME_LIMIT = "time_limit"  # stopped by the time limit; the incumbent is returned
    INFEASIBLE = "infeasible"
    ERROR = "error"


def quantize(values_m, unit_m: float = 1e-3) -> np.ndarray:
    """Metres -> integral model values in units of ``unit_m`` (round half to even)."""
    return np.round(np.asarray(values_m, dtype=np.float64) / unit_m)


def _distinct_rows(table: np.ndarray) -> bool:
    """Whether the rows of an int64 table (entries >= -1) are pairwise distinct."""
    return _distinct_keys(*table.T)


def _distinct_keys(*keys: np.ndarray) -> bool:
    """Whether the tuples ``(keys[0][i], keys[1][i], ...)`` (integer entries >= -1) are pairwise distinct.

    Each tuple becomes one mixed-radix integer, so a 1-D sort decides (``np.unique(axis=0)`` sorts a
    structured view and dominated a simulation round's model check); keys whose radix product
    could overflow int64 are compared row-wise.
    """
    radix = [int(k.max()) + 2 if len(k) else 1 for k in keys]
    if math.prod(float(r) for r in radix) >= 2.0**62:
        table = np.stack([np.asarray(k, dtype=np.int64) for k in keys], axis=1)
        return len(np.unique(table, axis=0)) == len(table)
    key = keys[0].astype(np.int64) + 1
    for col, base in zip(keys[1:], radix[1:], strict=True):
        key *= base
        key += col
        key += 1
    key.sort()
    return not (key[1:] == key[:-1]).any()


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def _field_names(cls: type) -> tuple[str, ...]:
    """A model class's dataclass field names, kept (``dataclasses.fields`` rebuilds them on every call)."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in fields(cls))
    return names


# --------------------------------------------------------------------- models
@dataclass(frozen=True, eq=False)
class _Model:
    structure: ClassVar[Structure]
    values: np.ndarray
    unit_m: float
    name: str

    # -- generic view --------------------------------------------------------
    @property
    def n_cols(self) -> int:
        return len(self.values)

    @property
    def n_rows(self) -> int:
        raise NotImplementedError

    def row_exact(self) -> np.ndarray:
        """Boolean per row: True for "= 1", False for "<= 1" (read-only; computed once per model, as
        :meth:`column_rows`: a simulation round asks for it several times)."""
        cached = self.__dict__.get("_row_exact_cache")
        if cached is None:
            cached = self._row_exact()
            cached.setflags(write=False)
            object.__setattr__(self, "_row_exact_cache", cached)
        return cached

    def _row_exact(self) -> np.ndarray:
        """:meth:`row_exact` computed from the model's sizes."""
        raise NotImplementedError

    def column_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Rows covered by each column as CSC ``(col_start, row_index)`` (read-only arrays).

        Computed once per model: a simulation round asks for them several times (size, program,
        verification, tie canonicalisation).
        """
        cached = self.__dict__.get("_column_rows_cache")
        if cached is None:
            start, rows = self._column_rows()
            start.setflags(write=False)
            rows.setflags(write=False)
            cached = (start, rows)
            object.__setattr__(self, "_column_rows_cache", cached)
        return cached

    def _column_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`column_rows` computed from the column arrays."""
        raise NotImplementedError

    def incidence(self) -> sp.csc_matrix:
        """The 0/1 row x column incidence matrix (rows as in :meth:`row_exact`)."""
        start, rows = self.column_rows()
        data = np.ones(len(rows), dtype=np.float64)
        return sp.csc_matrix((data, rows, start), shape=(self.n_rows, self.n_cols))

    def frozen(self) -> Self:
        """A copy whose arrays are read-only copies, validated again: what a backend is handed.

        Validation on construction does not cover arrays their builder changes afterwards (a plug-in
        strategy setting a value to NaN); the copy can no longer change, and is checked as it is.
        """
        if type(self) in _MODEL_CLASSES:  # as copy.copy copies them, without its protocol lookups
            twin = object.__new__(type(self))
            twin.__dict__.update(self.__dict__)
        else:
            twin = copy.copy(self)
        twin.__dict__.pop("_column_rows_cache", None)  # derived from the arrays as they were then
        twin.__dict__.pop("_row_exact_cache", None)
        for name in _field_names(type(self)):
            value = getattr(self, name)
            if isinstance(value, np.ndarray):
                mine = value.copy()
                mine.setflags(write=False)
                object.__setattr__(twin, name, mine)
        twin._validate()
        return twin

    def _validate(self) -> None:
        raise NotImplementedError

    def renamed(self, name: str) -> Self:
        """The same model under another name (arrays shared, no re-validation)."""
        twin = copy.copy(self)
        object.__setattr__(twin, "name", name)
        return twin

    @property
    def size(self) -> dict[str, int]:
        return {"rows": int(self.n_rows), "cols": int(self.n_cols), "nonzeros": int(self.column_rows()[0][-1])}

    # -- validation helpers --------------------------------------------------
    def _count(self, n, what: str) -> int:
        whole = isinstance(n, (int, np.integer)) and not isinstance(n, bool)
        if not (whole or (isinstance(n, (float, np.floating)) and math.isfinite(n) and n == int(n))):
            raise ModelError(f"model {self.name!r}: {what} {n!r} is not a whole number")
        return int(n)

    def _floats(self, raw) -> np.ndarray:
        try:
            return np.asarray(raw, dtype=np.float64)
        except (TypeError, ValueError):
            raise ModelError(f"model {self.name!r}: values must be numbers") from None

    def _indices(self, raw, what: str) -> np.ndarray:
        """``raw`` as int32 column indices, refusing what a cast would silently change (1.5, NaN, 2**40)."""
        arr = np.asarray(raw)
        if arr.ndim != 1 or (len(arr) and arr.dtype.kind not in "iuf"):
            raise ModelError(
                f"model {self.name!r}: {what} must be a one-dimensional array of integers "
                f"(got shape {arr.shape}, dtype {arr.dtype})"
            )
        if arr.dtype.kind == "i" and arr.dtype.itemsize <= 4:
            return arr.astype(np.int32, copy=False)
        if arr.dtype == np.int64 and arr.ndim == 1:  # a strategy's usual columns: one compiled range pass
            from rpbench.model import kernels  # compiled on first use

            bad = kernels.first_outside_int32(arr)
            if bad >= 0:
                raise ModelError(f"model {self.name!r}: {what} of column {bad} is {arr[bad].item()!r}, out of range")
            return arr.astype(np.int32)
        if len(arr):
            if arr.dtype.kind == "f" and not np.all(arr == np.round(arr)):  # NaN != NaN: refused too
                bad = int(np.flatnonzero(arr != np.round(arr))[0])
                raise ModelError(f"model {self.name!r}: {what} of column {bad} is {float(arr[bad])!r}, not an integer")
            if arr.min() < _INT32.min or arr.max() > _INT32.max:
                bad = int(np.flatnonzero((arr < _INT32.min) | (arr > _INT32.max))[0])
                raise ModelError(f"model {self.name!r}: {what} of column {bad} is {arr[bad].item()!r}, out of range")
        return arr.astype(np.int32)

    def _check_values(self) -> None:
        v = self.values
        if v.ndim != 1:
            raise ModelError(f"model {self.name!r}: values must be one-dimensional")
        total = float(np.abs(v).sum())  # NaN or infinite exactly when some value is: one pass for both checks
        if not math.isfinite(total):
            bad = int(np.flatnonzero(~np.isfinite(v))[0])
            raise ModelError(f"model {self.name!r}: value of column {bad} is {float(v[bad])!r}; values must be finite")
        if not np.all(v == np.round(v)):
            bad = int(np.flatnonzero(v != np.round(v))[0])
            raise ModelError(
                f"model {self.name!r}: value of column {bad} is {float(v[bad])!r}; values must be whole "
                f"multiples of unit_m={self.unit_m} (use rpbench.model.quantize)"
            )
        if total > MAX_EXACT_TOTAL:
            raise ModelError(f"model {self.name!r}: values too large for exact float64 sums; use a coarser unit_m")
        if not (self.unit_m > 0 and np.isfinite(self.unit_m)):
            raise ModelError(f"model {self.name!r}: unit_m={self.unit_m!r} must be a positive number")

    def _check_index(self, arr: np.ndarray, what: str, upper: int, allow_minus_one: bool = False) -> None:
        if len(arr) != self.n_cols:
            raise ModelError(f"model {self.name!r}: {what} has {len(arr)} entries for {self.n_cols} columns")
        lo = -1 if allow_minus_one else 0
        if len(arr) and (arr.min() < lo or arr.max() >= upper):
            c = int(np.flatnonzero((arr < lo) | (arr >= upper))[0])
            raise ModelError(f"model {self.name!r}: column {c} has {what} {int(arr[c])}, outside [{lo}, {upper - 1}]")

    def _check_unique(self, *keys: np.ndarray) -> None:
        if self.n_cols < 2:
            return
        if _distinct_keys(*keys):
            return
        table = np.stack([np.asarray(k, dtype=np.int64) for k in keys], axis=1)
        srt = np.lexsort(table.T[::-1])
        dup = np.flatnonzero((np.diff(table[srt], axis=0) == 0).all(axis=1))[0]
        raise ModelError(f"model {self.name!r}: columns {int(srt[dup])} and {int(srt[dup + 1])} are duplicates")

    # -- solutions -------------------------------------------------------------
    def objective_of(self, chosen) -> float:
        if not len(chosen):
            return 0.0
        if type(chosen) is not np.ndarray or chosen.dtype != np.int64:
            chosen = np.asarray(chosen, dtype=np.int64)
        return float(self.values[chosen].sum())

    def violations(self, chosen) -> list[str]:
        """Constraint violations of a 0/1 solution given as chosen column indices."""
        from rpbench.model import kernels  # compiled on first use

        chosen = np.asarray(chosen, dtype=np.int64)
        start, rows = self.column_rows()
        outside, twice, over, times, under = kernels.cover(start, rows, self.row_exact(), chosen)
        if outside:
            return [f"chosen column index outside 0..{self.n_cols - 1}"]
        out = ["a column is chosen twice"] if twice else []
        if over >= 0:
            out.append(f"row {over} is covered {times} times")
        if under >= 0:
            out.append(f"row {under} must be covered exactly once but is not covered")
        return out


@dataclass(frozen=True, eq=False)
class AssignmentModel(_Model):
    """One batch round: passengers x (vehicles + keep waiting).

    Rows ``0..n_passengers-1`` are passengers ("= 1"); rows
    ``n_passengers..n_passengers+n_vehicles-1`` are vehicles ("<= 1").
    ``col_vehicle == -1`` marks a passenger's keep-waiting option (at most one
    per passenger).
    """

    structure: ClassVar[Structure] = Structure.ASSIGNMENT
    n_passengers: int = 0
    n_vehicles: int = 0
    col_passenger: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    col_vehicle: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))

    def __init__(
        self,
        n_passengers: int,
        n_vehicles: int,
        col_passenger,
        col_vehicle,
        values,
        *,
        unit_m: float = 1e-3,
        name: str = "assignment",
    ):
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "n_passengers", self._count(n_passengers, "number of passengers"))
        object.__setattr__(self, "n_vehicles", self._count(n_vehicles, "number of vehicles"))
        object.__setattr__(self, "col_passenger", self._indices(col_passenger, "passenger"))
        object.__setattr__(self, "col_vehicle", self._indices(col_vehicle, "vehicle"))
        object.__setattr__(self, "values", self._floats(values))
        object.__setattr__(self, "unit_m", float(unit_m))
        self._validate()

    def _validate(self) -> None:
        from rpbench.model import kernels  # compiled on first use

        unit_ok = self.unit_m > 0 and np.isfinite(self.unit_m)
        if (
            unit_ok
            and self.values.ndim == 1
            and kernels.assignment_valid(
                self.n_passengers, self.n_vehicles, self.col_passenger, self.col_vehicle, self.values
            )
        ):
            return  # every check of _checks passes; they run to say what is wrong
        self._checks()

    def _checks(self) -> None:
        """The validation in Python, raising the :class:`ModelError` that says what is wrong."""
        if self.n_passengers < 0 or self.n_vehicles < 0:
            raise ModelError(f"model {self.name!r}: negative number of passengers or vehicles")
        self._check_values()
        self._check_index(self.col_passenger, "passenger", self.n_passengers)
        self._check_index(self.col_vehicle, "vehicle", self.n_vehicles, allow_minus_one=True)
        self._check_unique(self.col_passenger, self.col_vehicle)
        has_option = np.zeros(self.n_passengers, dtype=bool)
        has_option[self.col_passenger] = True
        if not has_option.all():
            p = int(np.flatnonzero(~has_option)[0])
            raise ModelError(
                f"model {self.name!r}: passenger {p} has no option at all; every passenger needs "
                "at least a keep-waiting column"
            )

    @property
    def n_rows(self) -> int:
        return self.n_passengers + self.n_vehicles

    def _row_exact(self) -> np.ndarray:
        exact = np.zeros(self.n_passengers + self.n_vehicles, bool)
        exact[: self.n_passengers] = True
        return exact

    def _column_rows(self) -> tuple[np.ndarray, np.ndarray]:
        from rpbench.model import kernels  # compiled on first use

        return kernels.assignment_column_rows(self.n_passengers, self.col_passenger, self.col_vehicle)

    @property
    def wait_columns(self) -> np.ndarray:
        return np.flatnonzero(self.col_vehicle < 0)


@dataclass(frozen=True, eq=False)
class TripPackingModel(_Model):
    """RTV trip assignment: columns are (trip of 1-2 requests, vehicle).

    Rows ``0..n_requests-1`` are requests, then ``n_vehicles`` vehicle rows;
    all "<= 1".  ``col_request2 == -1`` marks a one-request trip; otherwise
    ``col_request1 < col_request2``.
    """

    structure: ClassVar[Structure] = Structure.TRIP_PACKING
    n_requests: int = 0
    n_vehicles: int = 0
    col_vehicle: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    col_request1: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    col_request2: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))

    def __init__(
        self,
        n_requests: int,
        n_vehicles: int,
        col_vehicle,
        col_request1,
        col_request2,
        values,
        *,
        unit_m: float = 1e-3,
        name: str = "trip_packing",
    ):
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "n_requests", self._count(n_requests, "number of requests"))
        object.__setattr__(self, "n_vehicles", self._count(n_vehicles, "number of vehicles"))
        object.__setattr__(self, "col_vehicle", self._indices(col_vehicle, "vehicle"))
        object.__setattr__(self, "col_request1", self._indices(col_request1, "first request"))
        object.__setattr__(self, "col_request2", self._indices(col_request2, "second request"))
        object.__setattr__(self, "values", self._floats(values))
        object.__setattr__(self, "unit_m", float(unit_m))
        self._validate()

    def _validate(self) -> None:
        if self.n_requests < 0 or self.n_vehicles < 0:
            raise ModelError(f"model {self.name!r}: negative number of requests or vehicles")
        self._check_values()
        self._check_index(self.col_vehicle, "vehicle", self.n_vehicles)
        self._check_index(self.col_request1, "first request", self.n_requests)
        self._check_index(self.col_request2, "second request", self.n_requests, allow_minus_one=True)
        pair = self.col_request2 >= 0
        if np.any(self.col_request1[pair] >= self.col_request2[pair]):
            c = int(np.flatnonzero(pair & (self.col_request1 >= self.col_request2))[0])
            raise ModelError(
                f"model {self.name!r}: column {c} must list its requests in increasing order "
                f"(got {int(self.col_request1[c])}, {int(self.col_request2[c])})"
            )
        self._check_unique(self.col_vehicle, self.col_request1, self.col_request2)

    @property
    def n_rows(self) -> int:
        return self.n_requests + self.n_vehicles

    def _row_exact(self) -> np.ndarray:
        return np.zeros(self.n_rows, dtype=bool)

    def _column_rows(self) -> tuple[np.ndarray, np.ndarray]:
        pair = self.col_request2 >= 0
        counts = 2 + pair.astype(np.int64)
        start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        rows = np.empty(start[-1], dtype=np.int32)
        rows[start[:-1]] = self.col_request1
        rows[start[:-1][pair] + 1] = self.col_request2[pair]
        rows[start[1:] - 1] = self.n_requests + self.col_vehicle
        return start, rows


OBJECTIVES = ("weight", "cardinality_then_weight")


@dataclass(frozen=True, eq=False)
class PairingModel(_Model):
    """General-graph matching over orders: a column is a pair ``(a, b)``, ``a < b``.

    ``objective="weight"``: maximise the total value (Oracle-1).
    ``objective="cardinality_then_weight"``: maximise the number of pairs,
    then the total value among maximum matchings (Oracle-2).
    """

    structure: ClassVar[Structure] = Structure.PAIRING
    n_orders: int = 0
    col_a: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    col_b: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    objective: str = "weight"

    def __init__(
        self,
        n_orders: int,
        col_a,
        col_b,
        values,
        *,
        objective: str = "weight",
        unit_m: float = 1e-3,
        name: str = "pairing",
    ):
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "n_orders", self._count(n_orders, "number of orders"))
        object.__setattr__(self, "col_a", self._indices(col_a, "first order"))
        object.__setattr__(self, "col_b", self._indices(col_b, "second order"))
        object.__setattr__(self, "values", self._floats(values))
        object.__setattr__(self, "objective", objective)
        object.__setattr__(self, "unit_m", float(unit_m))
        self._validate()

    def _validate(self) -> None:
        if self.n_orders < 0:
            raise ModelError(f"model {self.name!r}: negative number of orders")
        if self.objective not in OBJECTIVES:
            raise ModelError(
                f"model {self.name!r}: objective {self.objective!r} unknown; expected one of {', '.join(OBJECTIVES)}"
            )
        self._check_values()
        self._check_index(self.col_a, "first order", self.n_orders)
        self._check_index(self.col_b, "second order", self.n_orders)
        if np.any(self.col_a >= self.col_b):
            c = int(np.flatnonzero(self.col_a >= self.col_b)[0])
            raise ModelError(
                f"model {self.name!r}: pair column {c} must satisfy a < b "
                f"(got {int(self.col_a[c])}, {int(self.col_b[c])})"
            )
        self._check_unique(self.col_a, self.col_b)

    @property
    def n_rows(self) -> int:
        return self.n_orders

    def _row_exact(self) -> np.ndarray:
        return np.zeros(self.n_orders, dtype=bool)

    def _column_rows(self) -> tuple[np.ndarray, np.ndarray]:
        start = np.arange(0, 2 * self.n_cols + 1, 2, dtype=np.int64)
        rows = np.empty(2 * self.n_cols, dtype=np.int32)
        rows[0::2] = self.col_a
        rows[1::2] = self.col_b
        return start, rows


Model = AssignmentModel | TripPackingModel | PairingModel
#: The model classes themselves (not subclasses, which may copy themselves otherwise).
_MODEL_CLASSES = (AssignmentModel, TripPackingModel, PairingModel)


# ------------------------------------------------------------------ solutions
@dataclass(frozen=True)
class Solution:
    """What a backend returns: chosen columns plus status, bound and timings.

    ``objective`` and ``bound`` are in model units (``Σ values[chosen]``);
    ``gap`` is relative, ``(bound - objective) / max(1, |objective|)``, when a
    bound is known.  Times are seconds: building the solver's own model,
    solving, and reading the answer back.  ``unique``: proven to be the only
    optimum, so there is no tie to resolve.
    """

    chosen: np.ndarray
    objective: float
    status: Status
    backend: str
    bound: float | None = None
    gap: float | None = None
    build_s: float = 0.0
    solve_s: float = 0.0
    extract_s: float = 0.0
    message: str = ""
    unique: bool = False

    @property
    def total_s(self) -> float:
        return self.build_s + self.solve_s + self.extract_s

    @property
    def cardinality(self) -> int:
        return len(self.chosen)

    def objective_m(self, model: _Model) -> float:
        return self.objective * model.unit_m


def make_solution(model: _Model, chosen, status: Status, backend: str, **kw) -> Solution:
    """A :class:`Solution` with ``chosen`` sorted and the objective recomputed from the model.

    Backends use this so the reported objective is always Σ values[chosen]
    exactly, never a solver's floating-point echo of it.  ``chosen`` must be
    distinct integral column indices: a boolean mask, a fractional index or
    a repeated one is a :class:`SolverError`, not something cast or
    deduplicated into a different answer.
    """
    if type(chosen) is np.ndarray and chosen.dtype == np.int64 and chosen.ndim == 1:
        # the usual case (a backend's column indices): a copy of our own, sorted and distinct
        from rpbench.model import kernels  # compiled on first use

        unique = chosen.copy()
        if not kernels.strictly_increasing(unique):
            unique = np.unique(unique)
            if len(unique) != len(chosen):
                raise SolverError(f"backend {backend!r} chose a column of {model.name!r} twice")
        unique.setflags(write=False)
        return Solution(chosen=unique, objective=model.objective_of(unique), status=status, backend=backend, **kw)
    raw = np.asarray(chosen)
    if raw.ndim != 1 or (len(raw) and raw.dtype.kind not in "iuf"):
        raise SolverError(
            f"backend {backend!r} chose columns of {model.name!r} as shape {raw.shape}, dtype {raw.dtype}; "
            "give a one-dimensional array of column indices (for a 0/1 vector x: np.flatnonzero(x > 0.5))"
        )
    if raw.dtype.kind == "f" and not np.all(raw == np.round(raw)):
        bad = int(np.flatnonzero(raw != np.round(raw))[0])
        raise SolverError(
            f"backend {backend!r} chose column index {float(raw[bad])!r} of {model.name!r}, not an integer"
        )
    unique = raw.astype(np.int64)  # a copy of our own
    if len(unique) > 1 and not (unique[1:] > unique[:-1]).all():  # already sorted and distinct: as np.unique
        unique = np.unique(unique)
    if len(unique) != len(raw):  # a 0/1 vector passed as indices, say: never silently deduplicated
        raise SolverError(f"backend {backend!r} chose a column of {model.name!r} twice")
    unique.setflags(write=False)
    return Solution(chosen=unique, objective=model.objective_of(unique), status=status, backend=backend, **kw)


def empty_solution(model: _Model, backend: str) -> Solution:
    """The optimal solution of a model with no columns (nothing to decide)."""
    return make_solution(model, np.zeros(0, np.int64), Status.OPTIMAL, backend, bound=0.0, gap=0.0)
