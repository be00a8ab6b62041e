"""Solver-agnostic models: validation with clear errors, structure views, solutions."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rpbench.exceptions import ModelError
from rpbench.model import (
    MAX_EXACT_TOTAL,
    AssignmentModel,
    PairingModel,
    Status,
    Structure,
    TripPackingModel,
    empty_solution,
    make_solution,
    quantize,
)


def assignment(**kw):
    args = dict(
        n_passengers=2, n_vehicles=2, col_passenger=[0, 0, 1, 1], col_vehicle=[0, -1, 1, -1], values=[-3, -5, -4, -6]
    )
    args.update(kw)
    return AssignmentModel(
        args.pop("n_passengers"),
        args.pop("n_vehicles"),
        args.pop("col_passenger"),
        args.pop("col_vehicle"),
        args.pop("values"),
        **args,
    )


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(values=[-3, float("nan"), -4, -6]), "value of column 1 is nan; values must be finite"),
        (dict(values=[-3, float("inf"), -4, -6]), "must be finite"),
        (dict(values=[-3, -5.5, -4, -6]), "whole multiples of unit_m"),
        (dict(col_vehicle=[0, -1, 2, -1]), "column 2 has vehicle 2, outside \\[-1, 1\\]"),
        (dict(col_passenger=[0, 0, 1, 3]), "column 3 has passenger 3, outside"),
        (dict(col_vehicle=[0, -1, 1]), "vehicle has 3 entries for 4 columns"),
        (dict(col_passenger=[0, 0, 0, 0], col_vehicle=[0, -1, 0, 1]), "columns 0 and 2 are duplicates"),
        (dict(n_passengers=3), "passenger 2 has no option at all"),
        (dict(n_vehicles=-1), "negative number"),
        (dict(unit_m=0.0), "unit_m=0.0 must be a positive number"),
        (dict(values=[MAX_EXACT_TOTAL, MAX_EXACT_TOTAL, 0, 0]), "too large for exact float64 sums"),
    ],
)
def test_assignment_validation(kw, match):
    with pytest.raises(ModelError, match=match):
        assignment(**kw)


@pytest.mark.parametrize(
    "args, kw, match",
    [
        ((3, [0, 1], [1, 3], [1, 2]), {}, "second order 3, outside"),
        ((3, [0, 2], [1, 1], [1, 2]), {}, "must satisfy a < b"),
        ((3, [0, 0], [1, 1], [1, 2]), {}, "duplicates"),
        ((3, [0], [1], [float("nan")]), {}, "must be finite"),
        ((3, [0], [1], [1]), {"objective": "pairs"}, "objective 'pairs' unknown"),
        ((-1, [], [], []), {}, "negative number of orders"),
    ],
)
def test_pairing_validation(args, kw, match):
    with pytest.raises(ModelError, match=match):
        PairingModel(*args, **kw)


@pytest.mark.parametrize(
    "args, match",
    [
        ((2, 1, [0], [1], [0], [1]), "must list its requests in increasing order"),
        ((2, 1, [1], [0], [-1], [1]), "vehicle 1, outside"),
        ((2, 1, [0, 0], [0, 0], [-1, -1], [1, 2]), "duplicates"),
        ((2, 1, [0], [0], [-2], [1]), "second request -2"),
    ],
)
def test_trip_packing_validation(args, match):
    with pytest.raises(ModelError, match=match):
        TripPackingModel(*args)


def test_models_are_frozen_and_typed():
    m = assignment()
    with pytest.raises(AttributeError):
        m.values = np.zeros(4)
    assert m.col_passenger.dtype == np.int32 and m.values.dtype == np.float64
    assert m.structure is Structure.ASSIGNMENT and m.size == {"rows": 4, "cols": 4, "nonzeros": 6}


def test_incidence_and_rows():
    m = assignment()
    A = m.incidence().toarray()
    assert A.tolist() == [[1, 1, 0, 0], [0, 0, 1, 1], [1, 0, 0, 0], [0, 0, 1, 0]]
    assert m.row_exact().tolist() == [True, True, False, False] and m.wait_columns.tolist() == [1, 3]
    t = TripPackingModel(3, 2, [0, 1], [0, 1], [2, -1], [5, 1])
    assert t.incidence().toarray()[:, 0].tolist() == [1, 0, 1, 1, 0] and not t.row_exact().any()
    p = PairingModel(3, [0, 1], [1, 2], [1, 1])
    assert p.incidence().toarray().tolist() == [[1, 0], [1, 1], [0, 1]]


def test_violations():
    m = assignment()
    assert m.violations([0, 2]) == [] and m.violations([1, 3]) == []
    assert m.violations([0]) == ["row 1 must be covered exactly once but is not covered"]
    assert m.violations([0, 1, 2]) == ["row 0 is covered 2 times"]
    assert "chosen twice" in m.violations([0, 0, 2])[0]
    assert m.violations([7]) == ["chosen column index outside 0..3"]
    p = PairingModel(3, [0, 1], [1, 2], [1, 1])
    assert p.violations([]) == [] and p.violations([0, 1]) == ["row 1 is covered 2 times"]


def test_violations_match_a_loop_on_random_choices():
    rng = np.random.default_rng(0)
    a, b = np.triu_indices(8, 1)
    p = PairingModel(8, a, b, np.ones(len(a)))
    start, rows = p.column_rows()
    for _ in range(50):
        chosen = rng.choice(p.n_cols, rng.integers(0, 6), replace=False)
        counts = np.zeros(8, int)
        for c in chosen:
            counts[rows[start[c] : start[c + 1]]] += 1
        assert (p.violations(chosen) == []) == (counts.max(initial=0) <= 1)


def test_solutions_recompute_the_objective():
    m = assignment()
    sol = make_solution(m, [2, 0], Status.OPTIMAL, "test", bound=-7.0)
    assert sol.chosen.tolist() == [0, 2] and sol.objective == -7.0 and sol.cardinality == 2
    assert sol.objective_m(m) == pytest.approx(-0.007) and sol.total_s == 0.0
    empty = empty_solution(PairingModel(0, [], [], []), "test")
    assert empty.status is Status.OPTIMAL and empty.objective == 0.0 and empty.gap == 0.0


def test_quantize_rounds_to_integral_units():
    assert quantize([1.2344, 1.2346, -0.0004]).tolist() == [1234.0, 1235.0, -0.0]
    assert quantize([1500.0], unit_m=1.0).tolist() == [1500.0]


def test_column_rows_are_computed_once_and_read_only():
    m = assignment()
    start, rows = m.column_rows()
    assert m.column_rows()[0] is start and m.column_rows()[1] is rows
    with pytest.raises(ValueError):
        rows[0] = 1


@pytest.mark.parametrize("seed", range(20))
def test_distinct_rows_matches_numpy_unique(seed):
    from rpbench.model import _distinct_rows

    rng = np.random.default_rng(seed)
    table = rng.integers(-1, 4, size=(int(rng.integers(1, 12)), int(rng.integers(1, 4)))).astype(np.int64)
    assert _distinct_rows(table) == (len(np.unique(table, axis=0)) == len(table))


def test_distinct_rows_with_huge_entries_falls_back_to_row_comparison():
    from rpbench.model import _distinct_rows

    big = 2**40
    assert _distinct_rows(np.array([[big, 1, big], [big, 2, big]], dtype=np.int64))
    assert not _distinct_rows(np.array([[big, 1, big], [big, 1, big]], dtype=np.int64))


@pytest.mark.parametrize(
    "col_passenger, message",
    [
        ([0, 0.5, 1], "passenger of column 1 is 0.5, not an integer"),
        ([0, np.nan, 1], "passenger of column 1 is nan, not an integer"),
        (np.array([0, 0, 2**40]), "passenger of column 2 is 1099511627776, out of range"),  # int32 would wrap it
        ([True, False, True], "one-dimensional array of integers"),
        ([[0], [0], [1]], "one-dimensional array of integers"),
    ],
)
def test_indices_a_cast_would_change_are_refused(col_passenger, message):
    with pytest.raises(ModelError, match=re.escape(message)):
        AssignmentModel(2, 1, col_passenger, [0, -1, -1], [3, 0, 0])
    with pytest.raises(ModelError, match="number of passengers 2.5 is not a whole number"):
        AssignmentModel(2.5, 1, [0, 0, 1], [0, -1, -1], [3, 0, 0])


def test_frozen_is_a_read_only_copy_validated_again():
    model = AssignmentModel(2, 1, [0, 0, 1], [0, -1, -1], [3, 0, 0])
    model.column_rows()  # cached from the arrays as they are now
    twin = model.frozen()
    assert not twin.values.flags.writeable and twin.values is not model.values
    model.col_vehicle[0] = -1  # a second wait column for passenger 0
    with pytest.raises(ModelError, match="columns 0 and 1 are duplicates"):
        model.frozen()
    assert twin.column_rows()[1].tolist() == [0, 2, 0, 1]  # the copy keeps what was checked


def _perturbed_assignments(seed: int, count: int):
    """Random assignment models, valid and broken in every way its validation checks."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n_p, n_v = int(rng.integers(0, 5)), int(rng.integers(0, 5))
        cols = [(p, v) for p in range(n_p) for v in range(-1, n_v) if v < 0 or rng.random() < 0.6]
        cp = np.array([c[0] for c in cols], np.int64)
        cv = np.array([c[1] for c in cols], np.int64)
        values = rng.integers(-50, 50, len(cols)).astype(np.float64)
        fault = int(rng.integers(0, 9))
        if len(cols):
            c = int(rng.integers(0, len(cols)))
            if fault == 1:
                values[c] = [np.nan, np.inf, 0.5][int(rng.integers(0, 3))]
            elif fault == 2:
                cp[c] = [n_p, -1][int(rng.integers(0, 2))]
            elif fault == 3:
                cv[c] = [n_v, -2][int(rng.integers(0, 2))]
            elif fault == 4 and len(cols) > 1:
                cp[c], cv[c] = cp[c - 1], cv[c - 1]  # a duplicate
            elif fault == 5:
                keep = cp != cp[c]  # a passenger without any column
                cp, cv, values = cp[keep], cv[keep], values[keep]
            elif fault == 6:
                values[c] = 2.0**53
        if fault == 7:
            n_p = -1
        yield n_p, n_v, cp.astype(np.int32), cv.astype(np.int32), values


def test_the_compiled_assignment_check_agrees_with_the_python_checks():
    from rpbench.model import kernels

    verdicts = set()
    for n_p, n_v, cp, cv, values in _perturbed_assignments(3, 2000):
        fast = kernels.assignment_valid(n_p, n_v, cp, cv, values)
        model = object.__new__(AssignmentModel)
        for name, value in [("name", "m"), ("n_passengers", n_p), ("n_vehicles", n_v), ("col_passenger", cp),
                            ("col_vehicle", cv), ("values", values), ("unit_m", 1e-3)]:  # fmt: skip
            object.__setattr__(model, name, value)
        try:
            model._checks()
            slow = True
        except ModelError:
            slow = False
        # near the float64 limit the kernel leaves the verdict to the Python checks
        assert fast == slow or (slow and np.abs(values).sum() > 2.0**52), (n_p, n_v, cp, cv, values)
        verdicts.add(fast)
    assert verdicts == {True, False}


def test_the_compiled_cover_check_words_violations_as_before():
    rng = np.random.default_rng(4)
    for n_p, n_v, cp, cv, values in _perturbed_assignments(5, 400):
        try:
            model = AssignmentModel(n_p, n_v, cp, cv, values)
        except ModelError:
            continue
        start, rows = model.column_rows()
        for _ in range(5):
            chosen = rng.integers(-1, model.n_cols + 1, int(rng.integers(0, 4))) if model.n_cols else []
            chosen = np.asarray(chosen, dtype=np.int64)
            want = []
            if len(chosen) and (chosen.min() < 0 or chosen.max() >= model.n_cols):
                want = [f"chosen column index outside 0..{model.n_cols - 1}"]
            else:
                if len(np.unique(chosen)) != len(chosen):
                    want.append("a column is chosen twice")
                counts = np.zeros(model.n_rows, np.int64)
                for c in chosen:
                    counts[rows[start[c] : start[c + 1]]] += 1
                over = np.flatnonzero(counts > 1)
                if len(over):
                    want.append(f"row {int(over[0])} is covered {int(counts[over[0]])} times")
                under = np.flatnonzero(model.row_exact() & (counts == 0))
                if len(under):
                    want.append(f"row {int(under[0])} must be covered exactly once but is not covered")
            assert model.violations(chosen) == want
